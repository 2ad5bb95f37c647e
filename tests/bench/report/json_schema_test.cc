#include "bench/report/json_schema.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace twin {
namespace {

using Json = nlohmann::ordered_json;

// "path: message" of the first violation, or "valid".
std::string Verdict(const Json& schema, const Json& doc, SchemaCheckOptions options = {}) {
  const auto bad = FirstSchemaViolation(schema, doc, options);
  return bad ? bad->path + ": " + bad->message : "valid";
}

const Json kMap = Json::parse(R"({
  "type": "object",
  "properties": {
    "name": {"type": "string", "description": "an annotation"},
    "kind": {"type": "string", "enum": ["floor", "wall"]},
    "n": {"type": "integer", "minimum": 2, "maximum": 8},
    "size": {"type": "number", "exclusiveMinimum": 0},
    "xyz": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
    "list": {"type": "array", "items": {"$ref": "#/definitions/item"}}
  },
  "required": ["name"],
  "additionalProperties": false,
  "definitions": {"item": {"type": "object", "properties": {"on": {"type": "boolean"}},
                           "additionalProperties": {"type": "number"}}}
})");

TEST(JsonSchema, AcceptsAValidDocument) {
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "kind": "wall", "n": 8, "size": 0.5,
      "xyz": [1, 2.5, 3], "list": [{"on": true, "gain": 2}]})")),
            "valid");
}

TEST(JsonSchema, NamesTheKeyPathAndWhatWasExpected) {
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": 3})")), "name: expected a string, got 3");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "kind": "flor"})")),
            "kind: expected one of floor, wall, got 'flor'");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "n": 1})")),
            "n: expected a value >= 2, got 1");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "n": 9})")),
            "n: expected a value <= 8, got 9");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "n": 2.5})")),
            "n: expected a whole number, got 2.5");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "size": 0})")),
            "size: expected a value > 0, got 0");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "xyz": [1, 2]})")),
            "xyz: expected a sequence of 3 items, got a sequence of 2 items");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "xyz": [1, "b", 3]})")),
            "xyz[1]: expected a number, got 'b'");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "nmae": 1})")),
            "nmae: unknown key 'nmae' (allowed: name, kind, n, size, xyz, list)");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"kind": "wall"})")), ": missing required key 'name'");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "list": [{}, {"on": 1}]})")),
            "list[1].on: expected true or false, got 1");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "list": [{"gain": "x"}]})")),
            "list[0].gain: expected a number, got 'x'");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"([1])")), ": expected a map, got a sequence of 1 items");
}

TEST(JsonSchema, AWholeFloatIsAnInteger) {  // as JSON Schema (draft 6 on) defines it
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": "a", "n": 4.0})")), "valid");
}

TEST(JsonSchema, TupleItemsAndAdditionalItems) {
  const Json schema = Json::parse(R"({"type": "array", "minItems": 1, "maxItems": 3,
      "items": [{"type": "string"}, {"type": "number"}], "additionalItems": false})");
  EXPECT_EQ(Verdict(schema, Json::parse(R"(["a", 1])")), "valid");
  EXPECT_EQ(Verdict(schema, Json::parse(R"([1, 1])")), "[0]: expected a string, got 1");
  EXPECT_EQ(Verdict(schema, Json::parse(R"(["a", 1, 2])")),
            ": expected a sequence of at most 2 items, got a sequence of 3 items");
  EXPECT_EQ(Verdict(schema, Json::parse(R"([])")),
            ": expected a sequence of at least 1 items, got a sequence of 0 items");
}

TEST(JsonSchema, OneOfRequiresExactlyOneKey) {
  const Json schema = Json::parse(R"({"type": "object",
      "oneOf": [{"required": ["rpy"]}, {"required": ["zyz"]}]})");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"rpy": 1})")), "valid");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"zyz": 1})")), "valid");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({})")),
            ": expected exactly one of the keys rpy, zyz, got none");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"rpy": 1, "zyz": 1})")),
            ": expected exactly one of the keys rpy, zyz, got 2");
}

TEST(JsonSchema, AnyOfRequiresAtLeastOneKey) {
  const Json schema = Json::parse(R"({"type": "object",
      "anyOf": [{"required": ["max"]}, {"required": ["min"]}]})");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"max": 1})")), "valid");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"max": 1, "min": 0})")), "valid");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"figure": "a"})")),
            ": expected at least one of the keys max, min, got none");
}

// A value of several kinds (`points: auto` or a list): the alternative of the value's type
// says what is wrong inside it; a value of no alternative's type names them all.
TEST(JsonSchema, OneOfKindsNamesTheKindOfTheValue) {
  const Json schema = Json::parse(R"({"oneOf": [
      {"type": "string", "enum": ["auto"]},
      {"type": "array", "minItems": 2,
       "items": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3}}]})");
  EXPECT_EQ(Verdict(schema, Json("auto")), "valid");
  EXPECT_EQ(Verdict(schema, Json::parse("[[1, 2, 3], [4, 5, 6]]")), "valid");
  EXPECT_EQ(Verdict(schema, Json("many")), ": expected one of auto, got 'many'");
  EXPECT_EQ(Verdict(schema, Json::parse("[[1, 2, 3], [4, 5]]")),
            "[1]: expected a sequence of 3 items, got a sequence of 2 items");
  EXPECT_EQ(Verdict(schema, Json(4)), ": expected 'auto' or a sequence, got 4");
}

TEST(JsonSchema, ExclusiveMaximumMultipleOfAndStringLengths) {
  const Json schema = Json::parse(R"({"type": "object", "properties": {
      "alpha": {"type": "number", "exclusiveMinimum": 0, "exclusiveMaximum": 0.5},
      "squares": {"type": "integer", "multipleOf": 2},
      "name": {"type": "string", "minLength": 1, "maxLength": 3}}})");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"alpha": 0.49, "squares": 4, "name": "abc"})")),
            "valid");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"alpha": 0.5})")),
            "alpha: expected a value < 0.5, got 0.5");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"squares": 5})")),
            "squares: expected a multiple of 2, got 5");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"name": ""})")),
            "name: expected a string of at least 1 characters, got 0");
  EXPECT_EQ(Verdict(schema, Json::parse(R"({"name": "abcd"})")),
            "name: expected a string of at most 3 characters, got 4");
  EXPECT_EQ(Verdict(schema, Json::parse("{\"name\": \"\u00e9\u00e9\u00e9\"}")), "valid");
}

TEST(JsonSchema, ScalarsAsStringsAcceptsNumbersForStrings) {
  SchemaCheckOptions lenient;
  lenient.scalars_as_strings = true;
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": 12})"), lenient), "valid");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": true})"), lenient), "valid");
  EXPECT_EQ(Verdict(kMap, Json::parse(R"({"name": [1]})"), lenient),
            "name: expected a string, got a sequence of 1 items");
}

TEST(JsonSchema, UnsupportedKeywordsAndReferencesAreProgrammingErrors) {
  EXPECT_THROW(FirstSchemaViolation(Json::parse(R"({"pattern": "a*"})"), Json("a")),
               std::logic_error);
  EXPECT_THROW(FirstSchemaViolation(Json::parse(R"({"$ref": "#/definitions/none"})"), Json(1)),
               std::logic_error);
  EXPECT_THROW(FirstSchemaViolation(Json::parse(R"({"type": "text"})"), Json(1)),
               std::logic_error);
}

}  // namespace
}  // namespace twin
