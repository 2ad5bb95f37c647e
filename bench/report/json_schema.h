// A small JSON Schema validator for exactly the subset that `twinbench schema`
// (bench/report/scenario_schema.h) emits, draft-07: type, properties, required,
// additionalProperties (false or a schema), enum, minimum, maximum, exclusiveMinimum,
// exclusiveMaximum, multipleOf, minLength, maxLength (in code points), items (a schema, or an
// array of schemas by position with additionalItems false), minItems, maxItems, oneOf, anyOf,
// and $ref to "#/definitions/NAME". Annotations ($schema, $id, title, description,
// default, definitions) are skipped; any other keyword is a programming error
// (std::logic_error), so that the generator cannot emit a rule nobody checks.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace twin {

/// The first place a document breaks its schema.
struct SchemaViolation {
  std::string path;     ///< key path of the value: "scenario.robots[0].name" ("" the document)
  std::string message;  ///< what was expected and what was found
};

struct SchemaCheckOptions {
  /// A number or true/false where a string is expected passes (a YAML scalar read as text, as
  /// the parsers of format-1 scenarios do).
  bool scalars_as_strings = false;
};

/// The first violation of `schema` by `document` (depth-first, in the document's key order),
/// or nullopt when it is valid.
std::optional<SchemaViolation> FirstSchemaViolation(const nlohmann::ordered_json& schema,
                                                    const nlohmann::ordered_json& document,
                                                    const SchemaCheckOptions& options = {});

}  // namespace twin
