// Helpers shared by the YAML readers of bench/ (robot models, scenarios): typed reads of
// yaml-cpp nodes, maps checked against their allowed keys, and errors that name the file, the
// line and the key path ("scenarios/a.yaml:12 scenario.board.square_mm"), plus the rotation
// conventions the files use.
#pragma once

#include <charconv>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "calib/common/frames.h"

namespace twin {

using YamlKeys = std::vector<std::string>;

/// Parses the whole of `text` as a base-10 integer of type T; nullopt if it is not one or
/// does not fit (std::from_chars takes no '+', no spaces and no fraction).
template <typename T>
std::optional<T> ParseWhole(const std::string& text) {
  T v{};
  const char* end = text.data() + text.size();
  const auto res = std::from_chars(text.data(), end, v);
  if (res.ec != std::errc() || res.ptr != end) return std::nullopt;
  return v;
}

/// "a, b, c" (for messages listing allowed keys or names).
std::string JoinNames(const std::vector<std::string>& names);

/// A short description of a node for messages: 'text', "a sequence of 3 items", "a map".
std::string DescribeNode(const YAML::Node& node);

/// "source:line path" (line 1-based; left out when the mark has none, path when empty).
std::string YamlWhere(const std::string& source, const YAML::Mark& mark, const std::string& path);

/// Parses YAML text; malformed YAML is an InputError naming source and line.
YAML::Node LoadYamlText(const std::string& text, const std::string& source);

/// Largest text input read whole (models, scenarios): a 12-joint model is about 10 KB, a
/// scenario about 5 KB; 4 MiB leaves room for comments and generated files while keeping a
/// mistaken path (a log, an image, a device) from being read into memory [bytes].
constexpr std::uintmax_t kMaxTextFileBytes = std::uintmax_t{4} << 20;

/// Refuses, without opening it, a path that is missing, not a regular file (a folder, a FIFO,
/// a device: reading those could block forever or never end) or larger than max_bytes.
/// Throws InputError naming the path.
void RequireRegularFile(const std::string& path, std::uintmax_t max_bytes);

/// The whole content of a regular file of at most max_bytes (RequireRegularFile); a missing
/// or unreadable file is an InputError naming it.
std::string ReadTextFile(const std::string& path, std::uintmax_t max_bytes = kMaxTextFileBytes);

/// A YAML node with its key path (e.g. "robot.links[2].alpha") for messages.
struct YamlField {
  YAML::Node node;
  std::string path;

  /// The field `child` found under `key` of this map.
  YamlField Child(const std::string& key, const YAML::Node& child) const;
  /// Item i of this sequence (the caller checks that it is a sequence of enough items).
  YamlField Item(std::size_t i) const;
};

/// Reads typed values from fields; every failure is an InputError naming source:line path.
class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  const std::string& source() const { return source_; }
  /// "source:line path" of a field.
  std::string Where(const YamlField& f) const;
  [[noreturn]] void Fail(const YamlField& f, const std::string& message) const;

  std::string String(const YamlField& f) const;
  /// A finite number.
  double Number(const YamlField& f) const;
  /// A sequence of exactly n finite numbers.
  std::vector<double> Numbers(const YamlField& f, std::size_t n) const;
  /// A sequence of 3 finite numbers.
  Vector3 Vector(const YamlField& f) const;
  /// A whole number (decimal digits, optional leading '-') that fits an int.
  int Integer(const YamlField& f) const;
  /// A sequence of exactly n whole numbers.
  std::vector<int> Integers(const YamlField& f, std::size_t n) const;
  /// A whole number >= 0 that fits 64 bits (seeds).
  std::uint64_t Unsigned64(const YamlField& f) const;
  /// true/false (YAML 1.1 spellings such as yes/no are accepted, as yaml-cpp does).
  bool Bool(const YamlField& f) const;

 private:
  std::string source_;
};

/// True when a field was written and is not null (an optional section that is present).
bool IsPresent(const YamlField& f);

/// The entries of a YAML map, checked against the allowed keys (unknown keys fail unless
/// accepted as extra; repeated keys always fail).
class YamlMap {
 public:
  enum class Extra { kReject, kAccept };

  YamlMap(const YamlReader& reader, YamlField map, const YamlKeys& allowed,
          Extra extra = Extra::kReject);

  /// The field under key; absent: nullopt, or an InputError when required.
  std::optional<YamlField> Find(const std::string& key, bool required) const;
  /// The field under a required key.
  YamlField Get(const std::string& key) const { return *Find(key, true); }
  bool Has(const std::string& key) const { return entries_.count(key) != 0; }
  /// Fields whose keys are not in `allowed` (only with Extra::kAccept), in file order.
  const std::vector<std::pair<std::string, YamlField>>& extra() const { return extra_; }
  /// The map itself (for messages about the whole map).
  const YamlField& field() const { return map_; }

 private:
  const YamlReader& reader_;
  YamlField map_;
  std::map<std::string, YAML::Node> entries_;
  std::vector<std::pair<std::string, YamlField>> extra_;
};

/// A pose from the xyz_mm entry and exactly one of rpy_deg (R = Rz(y) Ry(p) Rx(r)) or zyz_deg
/// (R = Rz(a) Ry(b) Rz(c)) of a map; the caller checked the map's keys. Angles must be within
/// +-360 deg (periodic: a larger value is a unit mistake).
Transform ReadPose(const YamlReader& r, const YamlMap& m);

/// The pose map at `f` (keys xyz_mm and one of rpy_deg, zyz_deg; ReadPose) whose translation
/// is at most max_translation_m long; `why` is the limit's reason in the message.
Transform ReadPoseWithin(const YamlReader& r, const YamlField& f, double max_translation_m,
                         const std::string& why);

/// R = Rz(y) Ry(p) Rx(r) for rpy = (r, p, y) [rad]: roll-pitch-yaw about fixed axes, as URDF.
Matrix3 RpyToRotation(const Vector3& rpy);

}  // namespace twin
