// The scenario format as a JSON Schema (draft-07), written from the key tables of
// bench/io/scenario_keys.h: `twinbench schema` prints it, schemas/scenario.schema.json is it
// (tests/docs/schema_test.sh fails when the two differ), and `twinbench check` validates a
// scenario against it before the semantic checks (ValidateScenarioSchema).
#pragma once

#include <map>
#include <string>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

namespace twin {

/// The JSON Schema of scenario files, generated from ScenarioSections().
nlohmann::ordered_json ScenarioSchema();

/// A YAML document as JSON, with the mark of every value (of a map entry: its key) by its key
/// path ("scenario.robots[0]",
/// "" the document) in `marks` (if given). Plain scalars are typed as YAML's core schema reads
/// them (null, true/false and the YAML 1.1 yes/no/on/off, whole numbers, finite numbers, else a
/// string); a quoted scalar is a string when `quoted_are_strings`, else typed like a plain one
/// (format 1). A map key that is not a scalar becomes "?".
nlohmann::ordered_json YamlToJson(const YAML::Node& node, bool quoted_are_strings,
                                  std::map<std::string, YAML::Mark>* marks = nullptr);

/// Validates the scenario file at `path` against ScenarioSchema(): strictly for format 2,
/// leniently about scalars for format 1 (a quoted number is a number, a number where a string
/// is expected is text: as the parser reads them). The first violation is an InputError whose
/// where() is "file:line key.path" and whose message says what was expected. A newer format
/// than the tool knows is refused first (ScenarioFormatOf). Malformed YAML: LoadYamlText's
/// InputError.
void ValidateScenarioSchema(const std::string& path);

/// `twinbench schema [--out FILE]`: writes the schema to stdout, or to FILE (refusing to write
/// over a file that is not a JSON Schema). Returns the exit code.
int RunSchemaVerb(const std::string& out);

}  // namespace twin
