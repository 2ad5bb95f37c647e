#include "bench/report/scenario_schema.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <set>
#include <stdexcept>

#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "bench/io/scenario_keys.h"
#include "bench/io/yaml_util.h"
#include "bench/report/json_schema.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

using Json = nlohmann::ordered_json;

// The key's description with its unit and default: "side of one square [mm]; default 10".
std::string Describe(const ScenarioKey& k) {
  std::string d = k.description;
  if (!d.empty() && d.back() == '.') d.pop_back();
  if (!k.unit.empty()) d += " [" + k.unit + "]";
  if (!k.default_text.empty()) d += "; default " + k.default_text;
  if (k.required) d += "; required";
  const auto robots = [](int n) { return n == 1 ? std::string("one robot") : "two robots"; };
  if (k.required_with_robots > 0) d += "; required with " + robots(k.required_with_robots);
  if (k.only_with_robots > 0) d += "; only with " + robots(k.only_with_robots);
  return d;
}

// A bound as JSON: a whole number without a fraction (2, not 2.0).
Json Bound(double v) {
  return v == std::floor(v) && std::abs(v) < 1e15 ? Json(static_cast<std::int64_t>(v)) : Json(v);
}

void AddRange(const ScenarioKey& k, Json* s) {
  if (k.minimum) (*s)[k.exclusive_minimum ? "exclusiveMinimum" : "minimum"] = Bound(*k.minimum);
  if (k.maximum) (*s)[k.exclusive_maximum ? "exclusiveMaximum" : "maximum"] = Bound(*k.maximum);
  if (k.multiple_of) (*s)["multipleOf"] = Bound(*k.multiple_of);
}

Json Ref(const std::string& section) { return Json{{"$ref", "#/definitions/" + section}}; }

Json Scalar(const char* type, const ScenarioKey& k) {
  Json s = {{"type", type}};
  if (!k.allowed.empty()) s["enum"] = k.allowed;
  if (!k.allowed_integers.empty()) s["enum"] = k.allowed_integers;
  AddRange(k, &s);
  return s;
}

Json Sequence(const ScenarioKey& k, Json items) {
  Json s = {{"type", "array"}, {"items", std::move(items)}};
  if (k.min_count > 0) s["minItems"] = k.min_count;
  if (k.max_count > 0) s["maxItems"] = k.max_count;
  return s;
}

// The schema of one key's value.
Json KeySchema(const ScenarioKey& k) {
  Json s;
  switch (k.type) {
    case KeyType::kString:
      s = Scalar("string", k);
      if (k.min_count > 0) s["minLength"] = k.min_count;
      if (k.max_count > 0) s["maxLength"] = k.max_count;
      break;
    case KeyType::kNumber: s = Scalar("number", k); break;
    case KeyType::kInteger: s = Scalar("integer", k); break;
    case KeyType::kUnsigned: s = {{"type", "integer"}, {"minimum", 0}}; break;
    case KeyType::kBoolean: s = {{"type", "boolean"}}; break;
    case KeyType::kNumbers: s = Sequence(k, Scalar("number", k)); break;
    case KeyType::kIntegers: s = Sequence(k, Scalar("integer", k)); break;
    case KeyType::kStrings: s = Sequence(k, Scalar("string", k)); break;
    case KeyType::kNumberLists: {
      Json item = {{"type", "array"}, {"items", Scalar("number", k)}};
      if (k.item_count > 0) {
        item["minItems"] = k.item_count;
        item["maxItems"] = k.item_count;
      }
      s = Sequence(k, item);
      break;
    }
    case KeyType::kSection: s = Ref(k.section); break;
    case KeyType::kSectionList:
      if (k.tuple.empty()) {
        s = Sequence(k, Ref(k.section));
      } else {
        Json items = Json::array();
        for (const std::string& t : k.tuple) items.push_back(Ref(t));
        s = Sequence(k, items);
        s["additionalItems"] = false;
      }
      break;
    case KeyType::kSectionMap:
      s = {{"type", "object"}, {"additionalProperties", Ref(k.section)}};
      break;
    case KeyType::kOpaque: s = {{"type", k.opaque_list ? "array" : "object"}}; break;
    case KeyType::kOneOf: {
      if (k.alternatives.size() < 2) {
        throw std::logic_error("scenario schema: key '" + k.key + "' has fewer than two kinds");
      }
      Json alternatives = Json::array();
      for (const ScenarioKey& a : k.alternatives) alternatives.push_back(KeySchema(a));
      s = {{"oneOf", alternatives}};
      break;
    }
  }
  // Beside a $ref, a description is an annotation only (draft-07 ignores $ref's siblings).
  s["description"] = Describe(k);
  return s;
}

Json SectionSchema(const ScenarioSection& section) {
  Json s = {{"type", "object"}, {"description", section.description}};
  Json props = Json::object();
  Json required = Json::array();
  for (const ScenarioKey& k : section.keys) {
    props[k.key] = KeySchema(k);
    if (k.required) required.push_back(k.key);
  }
  s["properties"] = props;
  if (!required.empty()) s["required"] = required;
  s["additionalProperties"] =
      section.extra_numbers ? Json{{"type", "number"}} : Json(false);
  if (section.exactly_one_of.size() > 1 || section.at_least_one_of.size() > 1) {
    throw std::logic_error("scenario schema: one exactly_one_of and one at_least_one_of group "
                           "per section");
  }
  // Each group as alternatives that each require one of its keys.
  const auto alternatives = [](const std::vector<std::string>& group) {
    Json a = Json::array();
    for (const std::string& key : group) a.push_back({{"required", {key}}});
    return a;
  };
  for (const auto& group : section.exactly_one_of) s["oneOf"] = alternatives(group);
  for (const auto& group : section.at_least_one_of) s["anyOf"] = alternatives(group);
  return s;
}

// A plain scalar as YAML's core schema types it (with YAML 1.1's yes/no/on/off, as yaml-cpp
// and the parsers read booleans).
Json TypedScalar(const std::string& text) {
  static const std::set<std::string> kNull = {"~", "null", "Null", "NULL"};
  static const std::set<std::string> kTrue = {"true", "True", "TRUE", "yes", "Yes",
                                              "YES",  "on",   "On",   "ON"};
  static const std::set<std::string> kFalse = {"false", "False", "FALSE", "no", "No",
                                               "NO",    "off",   "Off",   "OFF"};
  if (kNull.count(text)) return nullptr;
  if (kTrue.count(text)) return true;
  if (kFalse.count(text)) return false;
  if (const auto i = ParseWhole<std::int64_t>(text)) return *i;
  if (const auto u = ParseWhole<std::uint64_t>(text)) return *u;
  double d = 0.0;
  if (YAML::convert<double>::decode(YAML::Node(text), d) && std::isfinite(d)) return d;
  return text;
}

void Convert(const YAML::Node& node, bool quoted_are_strings, const std::string& path,
             std::map<std::string, YAML::Mark>* marks, Json* out) {
  if (marks) (*marks)[path] = node.Mark();
  if (node.IsMap()) {
    *out = Json::object();
    for (const auto& kv : node) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
      const std::string child = path.empty() ? key : path + "." + key;
      Convert(kv.second, quoted_are_strings, child, marks, &(*out)[key]);
      // A map's entry is located at its key (an unknown key, a block map's first line).
      if (marks) (*marks)[child] = kv.first.Mark();
    }
  } else if (node.IsSequence()) {
    *out = Json::array();
    for (std::size_t i = 0; i < node.size(); ++i) {
      out->push_back(nullptr);
      Convert(node[i], quoted_are_strings, path + "[" + std::to_string(i) + "]", marks,
              &out->back());
    }
  } else if (node.IsScalar()) {
    const bool quoted = node.Tag() == "!";
    *out = quoted && quoted_are_strings ? Json(node.Scalar()) : TypedScalar(node.Scalar());
  } else {
    *out = nullptr;
  }
}

}  // namespace

nlohmann::ordered_json ScenarioSchema() {
  const std::vector<ScenarioSection>& sections = ScenarioSections();
  Json schema = {{"$schema", "http://json-schema.org/draft-07/schema#"},
                 {"title", "twinbench scenario"}};
  const Json root = SectionSchema(sections.front());
  for (const auto& [key, value] : root.items()) schema[key] = value;
  schema["description"] = sections.front().description + " Generated by `twinbench schema` "
                          "from bench/io/scenario_keys.h; the newest format is " +
                          std::to_string(kScenarioFormat) + " (scenario.format).";
  Json definitions = Json::object();
  for (std::size_t i = 1; i < sections.size(); ++i) {
    definitions[sections[i].name] = SectionSchema(sections[i]);
  }
  schema["definitions"] = definitions;
  return schema;
}

nlohmann::ordered_json YamlToJson(const YAML::Node& node, bool quoted_are_strings,
                                  std::map<std::string, YAML::Mark>* marks) {
  Json out;
  Convert(node, quoted_are_strings, "", marks, &out);
  return out;
}

void ValidateScenarioSchema(const std::string& path) {
  const std::string text = ReadTextFile(path);
  const YAML::Node root = LoadYamlText(text, path);
  const bool strict = ScenarioFormatOf(root, path) >= 2;
  std::map<std::string, YAML::Mark> marks;
  const Json document = YamlToJson(root, strict, &marks);
  SchemaCheckOptions options;
  options.scalars_as_strings = !strict;
  static const Json schema = ScenarioSchema();
  if (const auto bad = FirstSchemaViolation(schema, document, options)) {
    const auto it = marks.find(bad->path);
    const YAML::Mark mark = it != marks.end() ? it->second : YAML::Mark::null_mark();
    throw InputError(YamlWhere(path, mark, bad->path), bad->message);
  }
}

int RunSchemaVerb(const std::string& out) {
  const std::string text = ScenarioSchema().dump(2) + "\n";
  if (out.empty()) {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return 0;
  }
  ValidateOutputFile(out, "--out", {"json-schema.org"});
  WriteTextFile(out, text);
  return 0;
}

}  // namespace twin
