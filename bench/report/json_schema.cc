#include "bench/report/json_schema.h"

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

namespace twin {
namespace {

using Json = nlohmann::ordered_json;

const std::set<std::string> kAnnotations = {"$schema", "$id",     "title",      "description",
                                            "default", "$comment", "definitions"};
const std::set<std::string> kKeywords = {
    "type",    "properties", "required", "additionalProperties", "enum", "minimum", "maximum",
    "exclusiveMinimum", "exclusiveMaximum", "multipleOf", "minLength", "maxLength", "items",
    "additionalItems", "minItems", "maxItems", "oneOf", "anyOf", "$ref"};

std::string Number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// The value as messages show it: 'text', 12, true, "a sequence of 3 items", "a map".
std::string Describe(const Json& v) {
  if (v.is_string()) return "'" + v.get<std::string>() + "'";
  if (v.is_array()) return "a sequence of " + std::to_string(v.size()) + " items";
  if (v.is_object()) return "a map";
  if (v.is_null()) return "nothing";
  return v.dump();
}

std::string TypeName(const std::string& type) {
  if (type == "string") return "a string";
  if (type == "number") return "a number";
  if (type == "integer") return "a whole number";
  if (type == "boolean") return "true or false";
  if (type == "object") return "a map";
  if (type == "array") return "a sequence";
  if (type == "null") return "nothing";
  throw std::logic_error("json schema: unknown type '" + type + "'");
}

bool IsWhole(const Json& v) {
  if (v.is_number_integer()) return true;
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return std::isfinite(d) && d == std::floor(d);
}

std::string Child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

class Checker {
 public:
  Checker(const Json& root, const SchemaCheckOptions& options) : root_(root), options_(options) {}

  std::optional<SchemaViolation> Check(const Json& schema, const Json& v,
                                       const std::string& path) const {
    if (!schema.is_object()) throw std::logic_error("json schema: a schema must be an object");
    for (const auto& [key, value] : schema.items()) {
      if (!kKeywords.count(key) && !kAnnotations.count(key)) {
        throw std::logic_error("json schema: keyword '" + key + "' is not supported");
      }
    }
    if (schema.contains("$ref")) return Check(Resolve(schema["$ref"]), v, path);
    if (auto bad = CheckType(schema, v, path)) return bad;
    if (auto bad = CheckEnum(schema, v, path)) return bad;
    if (auto bad = CheckRange(schema, v, path)) return bad;
    if (auto bad = CheckLength(schema, v, path)) return bad;
    if (v.is_object()) {
      if (auto bad = CheckObject(schema, v, path)) return bad;
    }
    if (v.is_array()) {
      if (auto bad = CheckArray(schema, v, path)) return bad;
    }
    if (schema.contains("oneOf")) {
      if (auto bad = CheckOneOf(schema["oneOf"], v, path)) return bad;
    }
    if (schema.contains("anyOf")) return CheckAnyOf(schema["anyOf"], v, path);
    return std::nullopt;
  }

 private:
  const Json& Resolve(const Json& ref) const {
    const std::string prefix = "#/definitions/";
    const std::string r = ref.get<std::string>();
    if (r.rfind(prefix, 0) != 0 || !root_.contains("definitions") ||
        !root_["definitions"].contains(r.substr(prefix.size()))) {
      throw std::logic_error("json schema: cannot resolve $ref '" + r + "'");
    }
    return root_["definitions"][r.substr(prefix.size())];
  }

  bool HasType(const Json& v, const std::string& type) const {
    if (type == "string") {
      return v.is_string() || (options_.scalars_as_strings && (v.is_number() || v.is_boolean()));
    }
    if (type == "number") return v.is_number();
    if (type == "integer") return IsWhole(v);
    if (type == "boolean") return v.is_boolean();
    if (type == "object") return v.is_object();
    if (type == "array") return v.is_array();
    if (type == "null") return v.is_null();
    TypeName(type);  // throws for an unknown type
    return false;
  }

  std::optional<SchemaViolation> CheckType(const Json& schema, const Json& v,
                                           const std::string& path) const {
    if (!schema.contains("type")) return std::nullopt;
    const std::string type = schema["type"].get<std::string>();
    if (HasType(v, type)) return std::nullopt;
    return SchemaViolation{path, "expected " + TypeName(type) + ", got " + Describe(v)};
  }

  std::optional<SchemaViolation> CheckEnum(const Json& schema, const Json& v,
                                           const std::string& path) const {
    if (!schema.contains("enum")) return std::nullopt;
    std::string names;
    for (const Json& e : schema["enum"]) {
      if (e == v) return std::nullopt;
      // A number read as text (scalars_as_strings) matches an enum of its spelling.
      if (options_.scalars_as_strings && e.is_string() && !v.is_string() &&
          !v.is_structured() && e.get<std::string>() == v.dump()) {
        return std::nullopt;
      }
      if (e.is_number() && v.is_number() && e.get<double>() == v.get<double>()) {
        return std::nullopt;
      }
      names += (names.empty() ? "" : ", ") + (e.is_string() ? e.get<std::string>() : e.dump());
    }
    return SchemaViolation{path, "expected one of " + names + ", got " + Describe(v)};
  }

  std::optional<SchemaViolation> CheckRange(const Json& schema, const Json& v,
                                            const std::string& path) const {
    if (!v.is_number()) return std::nullopt;
    const double x = v.get<double>();
    if (schema.contains("minimum") && !(x >= schema["minimum"].get<double>())) {
      return SchemaViolation{path, "expected a value >= " +
                                       Number(schema["minimum"].get<double>()) + ", got " +
                                       Describe(v)};
    }
    if (schema.contains("exclusiveMinimum") &&
        !(x > schema["exclusiveMinimum"].get<double>())) {
      return SchemaViolation{path, "expected a value > " +
                                       Number(schema["exclusiveMinimum"].get<double>()) +
                                       ", got " + Describe(v)};
    }
    if (schema.contains("maximum") && !(x <= schema["maximum"].get<double>())) {
      return SchemaViolation{path, "expected a value <= " +
                                       Number(schema["maximum"].get<double>()) + ", got " +
                                       Describe(v)};
    }
    if (schema.contains("exclusiveMaximum") &&
        !(x < schema["exclusiveMaximum"].get<double>())) {
      return SchemaViolation{path, "expected a value < " +
                                       Number(schema["exclusiveMaximum"].get<double>()) +
                                       ", got " + Describe(v)};
    }
    if (schema.contains("multipleOf")) {
      const double m = schema["multipleOf"].get<double>();
      const double q = x / m;
      if (!(std::isfinite(q) && q == std::floor(q))) {
        return SchemaViolation{path, "expected a multiple of " + Number(m) + ", got " +
                                         Describe(v)};
      }
    }
    return std::nullopt;
  }

  // A string's length in characters (UTF-8 code points, as JSON Schema counts them).
  std::optional<SchemaViolation> CheckLength(const Json& schema, const Json& v,
                                             const std::string& path) const {
    if (!v.is_string()) return std::nullopt;
    std::size_t n = 0;
    for (unsigned char c : v.get<std::string>()) n += (c & 0xC0) != 0x80;
    const std::size_t lo = schema.value("minLength", std::size_t{0});
    const std::size_t hi = schema.value("maxLength", static_cast<std::size_t>(-1));
    if (n >= lo && n <= hi) return std::nullopt;
    return SchemaViolation{path, "expected a string of " +
                                     (n < lo ? "at least " + std::to_string(lo)
                                             : "at most " + std::to_string(hi)) +
                                     " characters, got " + std::to_string(n)};
  }

  std::optional<SchemaViolation> CheckObject(const Json& schema, const Json& v,
                                             const std::string& path) const {
    const Json empty = Json::object();
    const Json& props = schema.contains("properties") ? schema["properties"] : empty;
    for (const auto& [key, value] : v.items()) {
      if (props.contains(key)) {
        if (auto bad = Check(props[key], value, Child(path, key))) return bad;
        continue;
      }
      if (!schema.contains("additionalProperties")) continue;
      const Json& extra = schema["additionalProperties"];
      if (extra.is_boolean()) {
        if (extra.get<bool>()) continue;
        std::string allowed;
        for (const auto& [name, s] : props.items()) allowed += (allowed.empty() ? "" : ", ") + name;
        return SchemaViolation{Child(path, key),
                               "unknown key '" + key + "' (allowed: " + allowed + ")"};
      }
      if (auto bad = Check(extra, value, Child(path, key))) return bad;
    }
    if (schema.contains("required")) {
      for (const Json& key : schema["required"]) {
        if (!v.contains(key.get<std::string>())) {
          return SchemaViolation{path, "missing required key '" + key.get<std::string>() + "'"};
        }
      }
    }
    return std::nullopt;
  }

  std::optional<SchemaViolation> CheckArray(const Json& schema, const Json& v,
                                            const std::string& path) const {
    const std::size_t n = v.size();
    const std::size_t lo = schema.value("minItems", std::size_t{0});
    const std::size_t hi = schema.value("maxItems", static_cast<std::size_t>(-1));
    if (n < lo || n > hi) {
      const std::string count = lo == hi                 ? std::to_string(lo)
                                : n < lo                 ? "at least " + std::to_string(lo)
                                                         : "at most " + std::to_string(hi);
      return SchemaViolation{path, "expected a sequence of " + count + " items, got " +
                                       Describe(v)};
    }
    if (!schema.contains("items")) return std::nullopt;
    const Json& items = schema["items"];
    for (std::size_t i = 0; i < n; ++i) {
      const std::string item_path = path + "[" + std::to_string(i) + "]";
      if (items.is_array()) {
        if (i >= items.size()) {
          if (schema.contains("additionalItems") && !schema["additionalItems"].get<bool>()) {
            return SchemaViolation{path, "expected a sequence of at most " +
                                             std::to_string(items.size()) + " items, got " +
                                             Describe(v)};
          }
          continue;
        }
        if (auto bad = Check(items[i], v[i], item_path)) return bad;
      } else if (auto bad = Check(items, v[i], item_path)) {
        return bad;
      }
    }
    return std::nullopt;
  }

  // The keys of alternatives that each only require one key ("rpy, zyz"), or "" when some
  // alternative is more than that.
  static std::string KeyAlternatives(const Json& alternatives) {
    std::string keys;
    for (const Json& a : alternatives) {
      if (!(a.size() == 1 && a.contains("required") && a["required"].size() == 1)) return "";
      keys += (keys.empty() ? "" : ", ") + a["required"][0].get<std::string>();
    }
    return keys;
  }

  // An alternative as messages name it: its enum ("'auto'") or its type ("a sequence").
  static std::string Summary(const Json& a) {
    if (a.contains("enum")) {
      std::string names;
      for (const Json& e : a["enum"]) {
        names += (names.empty() ? "" : ", ") + (e.is_string() ? "'" + e.get<std::string>() + "'"
                                                              : e.dump());
      }
      return names;
    }
    if (a.contains("type")) return TypeName(a["type"].get<std::string>());
    return "an alternative";
  }

  // Exactly one alternative must hold. Alternatives that each only require one key (a pose's
  // rotation) are named as keys; of alternatives of other kinds (`points: auto` or a list),
  // the one of the value's type explains what is wrong inside it.
  std::optional<SchemaViolation> CheckOneOf(const Json& alternatives, const Json& v,
                                            const std::string& path) const {
    int holding = 0;
    for (const Json& a : alternatives) {
      if (!Check(a, v, path)) ++holding;
    }
    if (holding == 1) return std::nullopt;
    const std::string keys = KeyAlternatives(alternatives);
    if (!keys.empty()) {
      return SchemaViolation{path, "expected exactly one of the keys " + keys + ", got " +
                                       (holding == 0 ? "none" : std::to_string(holding))};
    }
    if (holding == 0) {
      const Json* of_type = nullptr;
      int typed = 0;
      std::string kinds;
      for (const Json& a : alternatives) {
        kinds += (kinds.empty() ? "" : " or ") + Summary(a);
        if (a.contains("type") && HasType(v, a["type"].get<std::string>())) {
          of_type = &a;
          ++typed;
        }
      }
      if (typed == 1) return Check(*of_type, v, path);
      return SchemaViolation{path, "expected " + kinds + ", got " + Describe(v)};
    }
    return SchemaViolation{path, "expected exactly one of " + std::to_string(alternatives.size()) +
                                     " alternatives to hold, " + std::to_string(holding) +
                                     " did"};
  }

  // At least one alternative must hold (a criterion's max and/or min).
  std::optional<SchemaViolation> CheckAnyOf(const Json& alternatives, const Json& v,
                                            const std::string& path) const {
    std::optional<SchemaViolation> first;
    for (const Json& a : alternatives) {
      auto bad = Check(a, v, path);
      if (!bad) return std::nullopt;
      if (!first) first = bad;
    }
    const std::string keys = KeyAlternatives(alternatives);
    if (!keys.empty()) {
      return SchemaViolation{path, "expected at least one of the keys " + keys + ", got none"};
    }
    return first;
  }

  const Json& root_;
  SchemaCheckOptions options_;
};

}  // namespace

std::optional<SchemaViolation> FirstSchemaViolation(const nlohmann::ordered_json& schema,
                                                    const nlohmann::ordered_json& document,
                                                    const SchemaCheckOptions& options) {
  return Checker(schema, options).Check(schema, document, "");
}

}  // namespace twin
