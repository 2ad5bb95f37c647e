#include "bench/io/yaml_util.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <ios>
#include <iterator>

#include "calib/identification/base_calibration.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

// Parses the whole of `text` as a base-10 integer of type T; nullopt if it is not one or
// does not fit (std::from_chars takes no '+', no spaces and no fraction).
template <typename T>
std::optional<T> ParseWhole(const std::string& text) {
  T v{};
  const char* end = text.data() + text.size();
  const auto res = std::from_chars(text.data(), end, v);
  if (res.ec != std::errc() || res.ptr != end) return std::nullopt;
  return v;
}

}  // namespace

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& k : names) out += (out.empty() ? "" : ", ") + k;
  return out;
}

std::string DescribeNode(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a sequence of " + std::to_string(node.size()) + " items";
  if (node.IsMap()) return "a map";
  return "nothing";
}

std::string YamlWhere(const std::string& source, const YAML::Mark& mark,
                      const std::string& path) {
  std::string where = source;
  if (mark.line >= 0) where += ":" + std::to_string(mark.line + 1);
  if (!path.empty()) where += " " + path;
  return where;
}

YAML::Node LoadYamlText(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(YamlWhere(source, e.mark, ""), "malformed YAML: " + e.msg);
  }
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file");
  std::string text;
  try {  // reading a directory throws from the stream buffer
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  } catch (const std::ios_base::failure& e) {
    throw InputError(path, std::string("cannot read file: ") + e.what());
  }
  if (in.bad()) throw InputError(path, "cannot read file");
  return text;
}

YamlField YamlField::Child(const std::string& key, const YAML::Node& child) const {
  return {child, path.empty() ? key : path + "." + key};
}

YamlField YamlField::Item(std::size_t i) const {
  return {node[i], path + "[" + std::to_string(i) + "]"};
}

std::string YamlReader::Where(const YamlField& f) const {
  return YamlWhere(source_, f.node.Mark(), f.path);
}

void YamlReader::Fail(const YamlField& f, const std::string& message) const {
  throw InputError(Where(f), message);
}

std::string YamlReader::String(const YamlField& f) const {
  if (!f.node.IsScalar()) Fail(f, "expected a string, got " + DescribeNode(f.node));
  return f.node.Scalar();
}

double YamlReader::Number(const YamlField& f) const {
  double v = 0.0;
  if (!f.node.IsScalar() || !YAML::convert<double>::decode(f.node, v)) {
    Fail(f, "expected a number, got " + DescribeNode(f.node));
  }
  if (!std::isfinite(v)) Fail(f, "expected a finite number, got " + DescribeNode(f.node));
  return v;
}

std::vector<double> YamlReader::Numbers(const YamlField& f, std::size_t n) const {
  if (!f.node.IsSequence() || f.node.size() != n) {
    Fail(f, "expected a sequence of " + std::to_string(n) + " numbers, got " +
                DescribeNode(f.node));
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(Number(f.Item(i)));
  return out;
}

Vector3 YamlReader::Vector(const YamlField& f) const {
  const std::vector<double> v = Numbers(f, 3);
  return Vector3(v[0], v[1], v[2]);
}

int YamlReader::Integer(const YamlField& f) const {
  const std::optional<int> v =
      f.node.IsScalar() ? ParseWhole<int>(f.node.Scalar()) : std::nullopt;
  if (!v) Fail(f, "expected a whole number, got " + DescribeNode(f.node));
  return *v;
}

std::vector<int> YamlReader::Integers(const YamlField& f, std::size_t n) const {
  if (!f.node.IsSequence() || f.node.size() != n) {
    Fail(f, "expected a sequence of " + std::to_string(n) + " whole numbers, got " +
                DescribeNode(f.node));
  }
  std::vector<int> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(Integer(f.Item(i)));
  return out;
}

std::uint64_t YamlReader::Unsigned64(const YamlField& f) const {
  const std::optional<std::uint64_t> v =
      f.node.IsScalar() ? ParseWhole<std::uint64_t>(f.node.Scalar()) : std::nullopt;
  if (!v) Fail(f, "expected a whole number from 0 to 2^64 - 1, got " + DescribeNode(f.node));
  return *v;
}

bool YamlReader::Bool(const YamlField& f) const {
  bool v = false;
  if (!f.node.IsScalar() || !YAML::convert<bool>::decode(f.node, v)) {
    Fail(f, "expected true or false, got " + DescribeNode(f.node));
  }
  return v;
}

YamlMap::YamlMap(const YamlReader& reader, YamlField map, const YamlKeys& allowed, Extra extra)
    : reader_(reader), map_(std::move(map)) {
  if (!map_.node.IsMap()) {
    reader_.Fail(map_, "expected a map with keys (" + JoinNames(allowed) + "), got " +
                           DescribeNode(map_.node));
  }
  for (const auto& kv : map_.node) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
    const YamlField key_field = map_.Child(key, kv.first);
    const bool known = std::find(allowed.begin(), allowed.end(), key) != allowed.end();
    if (!known && extra == Extra::kReject) {
      reader_.Fail(key_field, "unknown key '" + key + "' (allowed: " + JoinNames(allowed) + ")");
    }
    if (!entries_.emplace(key, kv.second).second) {
      reader_.Fail(key_field, "duplicate key '" + key + "'");
    }
    if (!known) extra_.emplace_back(key, map_.Child(key, kv.second));
  }
}

std::optional<YamlField> YamlMap::Find(const std::string& key, bool required) const {
  const auto it = entries_.find(key);
  if (it != entries_.end()) return map_.Child(key, it->second);
  if (required) reader_.Fail(map_, "missing required key '" + key + "'");
  return std::nullopt;
}

bool IsPresent(const YamlField& f) { return f.node.IsDefined() && !f.node.IsNull(); }

Transform ReadPose(const YamlReader& r, const YamlMap& m) {
  const std::optional<YamlField> rpy = m.Find("rpy_deg", false);
  const std::optional<YamlField> zyz = m.Find("zyz_deg", false);
  if (rpy && zyz) r.Fail(*zyz, "expected exactly one of rpy_deg and zyz_deg, got both");
  if (!rpy && !zyz) {
    r.Fail(m.field(), "missing rotation: expected exactly one of rpy_deg (fixed axes, "
                      "R = Rz(y) Ry(p) Rx(r)) or zyz_deg (R = Rz(a) Ry(b) Rz(c))");
  }
  const Vector3 deg = r.Vector(rpy ? *rpy : *zyz);
  const Vector3 rad(DegToRad(deg.x()), DegToRad(deg.y()), DegToRad(deg.z()));
  Transform X = Transform::Identity();
  X.translation() = r.Vector(m.Get("xyz_mm")) / 1000.0;
  X.linear() = rpy ? RpyToRotation(rad) : RotationFromZyz(rad);
  return X;
}

Matrix3 RpyToRotation(const Vector3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vector3::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Vector3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vector3::UnitX()))
      .toRotationMatrix();
}

}  // namespace twin
