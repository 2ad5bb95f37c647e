// The keys of a scenario file, one table per section: each key's type, unit, whether it is
// required (or its default), its range or allowed values and what it means. This is the one
// source of truth for the format: the scenario parser (bench/io/scenario.cc) and the parsers of
// the procedure sections (calibration: bench/io/calibration_config.cc and, for its and the
// tracker's diagnosis:, bench/io/diagnosis_config.cc; handclasp: bench/runs/handclasp_run.cc;
// tracker_calibration: bench/runs/tracker_run.cc; acceptance: bench/report/acceptance.cc) check
// every map's keys against these tables, and `twinbench schema` (bench/report/scenario_schema.h)
// walks them to write schemas/scenario.schema.json, the JSON Schema that `twinbench check` and
// editors validate scenario files against. A range here only restates a check the parser or
// ValidateTwinSpec makes anyway (the schema reports it earlier, by key path), never a new one;
// checks across keys or against other sections (robot names, lengths of translations, min <=
// max, products of counts) stay with the parsers.
//
// Format versions (scenario.format): 1 is every file without the key; 2 adds the key itself,
// and `twinbench check` validates a format-2 file strictly against the schema (a quoted "834"
// is a string, not a number; a string that reads as a number or true/false must be quoted).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "bench/io/yaml_util.h"

namespace twin {

/// The newest scenario format this twinbench reads (scenario.format).
constexpr int kScenarioFormat = 2;

/// One line for the notice printed for a scenario without `format` (format 1): what format 2
/// changed.
std::string ScenarioFormatNotice();

/// What a key's value is.
enum class KeyType {
  kString,
  kNumber,       ///< a finite number
  kInteger,      ///< a whole number that fits an int
  kUnsigned,     ///< a whole number >= 0 that fits 64 bits (seeds)
  kBoolean,
  kNumbers,      ///< a sequence of numbers (count or min_count..max_count items)
  kIntegers,     ///< a sequence of whole numbers
  kNumberLists,  ///< a sequence of sequences of numbers, each item_count long (points)
  kStrings,      ///< a sequence of strings
  kSection,      ///< a map whose keys are in the table `section`
  kSectionList,  ///< a sequence of maps of the table `section` (or `tuple` sections by position)
  kSectionMap,   ///< a map of any keys (names), each value a map of the table `section`
  kOpaque,       ///< a section another module parses: only its kind (map or list) is checked
  kOneOf,        ///< exactly one of the value kinds in `alternatives` (`points: auto` or a list)
};

/// A key of a section.
struct ScenarioKey {
  std::string key;
  KeyType type = KeyType::kString;
  bool required = false;
  int required_with_robots = 0;      ///< required only in a cell of this many robots (0: none)
  int only_with_robots = 0;          ///< allowed only in a cell of this many robots (0: any)
  std::string unit;                  ///< "mm", "deg", "px", ... ("" where none)
  std::string default_text;          ///< the default as documented ("" where none)
  std::optional<double> minimum;     ///< for numbers, or each item of a sequence
  std::optional<double> maximum;
  bool exclusive_minimum = false;    ///< minimum excluded (> instead of >=)
  bool exclusive_maximum = false;    ///< maximum excluded (< instead of <=)
  std::optional<double> multiple_of; ///< numbers (or items) must be whole multiples (even: 2)
  std::vector<std::string> allowed;  ///< allowed strings ("" none)
  std::vector<int> allowed_integers; ///< allowed whole numbers (empty: none)
  int min_count = 0, max_count = 0;  ///< sequence lengths, a kString's length (0: no bound)
  int item_count = 0;                ///< kNumberLists: the length of each item
  std::string section;               ///< the nested table (kSection, kSectionList, kSectionMap)
  std::vector<std::string> tuple;    ///< kSectionList: a table per position instead
  bool opaque_list = false;          ///< kOpaque: a sequence (else a map)
  std::vector<ScenarioKey> alternatives;  ///< kOneOf: the kinds of value (keys without a name)
  std::string description;

  // Builders, so that a table reads as a list of keys.
  ScenarioKey& Required() { required = true; return *this; }
  ScenarioKey& RequiredWithRobots(int n) { required_with_robots = n; return *this; }
  ScenarioKey& OnlyWithRobots(int n) { only_with_robots = n; return *this; }
  ScenarioKey& Unit(std::string u) { unit = std::move(u); return *this; }
  ScenarioKey& Default(std::string d) { default_text = std::move(d); return *this; }
  ScenarioKey& Min(double v) { minimum = v; return *this; }
  ScenarioKey& Above(double v) { minimum = v; exclusive_minimum = true; return *this; }
  ScenarioKey& Max(double v) { maximum = v; return *this; }
  ScenarioKey& Below(double v) { maximum = v; exclusive_maximum = true; return *this; }
  ScenarioKey& MultipleOf(double v) { multiple_of = v; return *this; }
  ScenarioKey& ItemCount(int n) { item_count = n; return *this; }
  ScenarioKey& Either(std::vector<ScenarioKey> v) { alternatives = std::move(v); return *this; }
  ScenarioKey& Count(int n) { min_count = max_count = n; return *this; }
  ScenarioKey& Counts(int lo, int hi) { min_count = lo; max_count = hi; return *this; }
  ScenarioKey& OneOf(std::vector<std::string> v) { allowed = std::move(v); return *this; }
  ScenarioKey& OneOfIntegers(std::vector<int> v) { allowed_integers = std::move(v); return *this; }
  ScenarioKey& Of(std::string s) { section = std::move(s); return *this; }
  ScenarioKey& Doc(std::string d) { description = std::move(d); return *this; }
};

/// A section (a map) of a scenario file.
struct ScenarioSection {
  std::string name;  ///< "scenario", "camera", "pose", ...
  std::string description;
  std::vector<ScenarioKey> keys;
  /// Keys not in `keys` are accepted when they hold a number (an effect's parameters).
  bool extra_numbers = false;
  /// Exactly one key of each group must be present (a pose's rotation).
  std::vector<std::vector<std::string>> exactly_one_of = {};
  /// At least one key of each group must be present (a criterion's max and/or min).
  std::vector<std::vector<std::string>> at_least_one_of = {};
};

/// Every section, the root (name "root", the file itself) first.
const std::vector<ScenarioSection>& ScenarioSections();

/// The section called `name`; a name that is not a section is a programming error
/// (std::logic_error).
const ScenarioSection& ScenarioSectionNamed(const std::string& name);

/// The keys of section `name`, for YamlMap's check of unknown keys.
YamlKeys ScenarioKeyNames(const std::string& name);

/// The key `key` of section `name` (std::logic_error where there is none).
const ScenarioKey& ScenarioKeyOf(const std::string& name, const std::string& key);

}  // namespace twin
