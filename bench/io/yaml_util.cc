#include "bench/io/yaml_util.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <ios>
#include <iterator>
#include <sstream>
#include <vector>

#include "calib/identification/base_calibration.h"
#include "bench/io/output_files.h"
#include "calib/common/errors.h"

namespace twin {

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

namespace {

// A quoted scalar whose closing quote is lines away and which swallowed text that looks like
// "key:" lines is almost always an unclosed quote: yaml-cpp reads on to the next quote and the
// keys after it then seem missing. Returns the first such scalar's mark and the swallowed key.
bool FindRunawayQuote(const YAML::Node& node, const std::string& text, YAML::Mark* mark,
                      std::string* swallowed) {
  if (node.IsMap()) {
    for (const auto& kv : node) {
      if (FindRunawayQuote(kv.second, text, mark, swallowed)) return true;
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) {
      if (FindRunawayQuote(item, text, mark, swallowed)) return true;
    }
  } else if (node.IsScalar() && node.Tag() == "!") {
    const YAML::Mark m = node.Mark();
    if (m.pos < 0 || static_cast<std::size_t>(m.pos) >= text.size()) return false;
    const char quote = text[static_cast<std::size_t>(m.pos)];
    if (quote != '\'' && quote != '"') return false;
    std::size_t end = m.pos + 1;
    for (; end < text.size(); ++end) {
      if (quote == '"' && text[end] == '\\') {
        ++end;
      } else if (text[end] == quote) {
        if (quote == '\'' && end + 1 < text.size() && text[end + 1] == '\'') {
          ++end;  // '' inside single quotes
        } else {
          break;
        }
      }
    }
    const std::string inside = text.substr(m.pos + 1, end - m.pos - 1);
    std::size_t nl = inside.find('\n');
    while (nl != std::string::npos) {
      std::size_t k = nl + 1;
      while (k < inside.size() && (inside[k] == ' ' || inside[k] == '\t' || inside[k] == '-')) ++k;
      std::size_t e = k;
      while (e < inside.size() && (std::isalnum(static_cast<unsigned char>(inside[e])) ||
                                   inside[e] == '_')) {
        ++e;
      }
      if (e > k && e < inside.size() && inside[e] == ':') {
        *mark = m;
        *swallowed = inside.substr(k, e - k);
        return true;
      }
      nl = inside.find('\n', nl + 1);
    }
  }
  return false;
}

// For a file that does not parse: the first line (0-based) whose value opens a quote that is
// not closed on that line, followed by a line that looks like a key; -1 if none.
int UnclosedQuoteLine(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == '\n') {
      lines.push_back(text.substr(start, i - start));
      start = i + 1;
    }
  }
  const auto looks_like_key = [](const std::string& l) {
    std::size_t k = l.find_first_not_of(" \t");
    if (k == std::string::npos) return false;
    if (l[k] == '-') return true;
    const std::size_t e = l.find_first_not_of(
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_", k);
    return e != k && e != std::string::npos && l[e] == ':';
  };
  for (std::size_t n = 0; n + 1 < lines.size(); ++n) {
    const std::string& l = lines[n];
    const std::size_t hash = l.find_first_of("#'\"");
    if (hash == std::string::npos || l[hash] == '#') continue;
    // The quote must open a value: after "key: " or "- ".
    const std::size_t before = l.find_last_not_of(' ', hash == 0 ? 0 : hash - 1);
    if (hash == 0 || before == std::string::npos || (l[before] != ':' && l[before] != '-')) {
      continue;
    }
    const char quote = l[hash];
    bool closed = false;
    for (std::size_t i = hash + 1; i < l.size(); ++i) {
      if (quote == '"' && l[i] == '\\') {
        ++i;
      } else if (l[i] == quote) {
        if (quote == '\'' && i + 1 < l.size() && l[i + 1] == '\'') {
          ++i;
        } else {
          closed = true;
          break;
        }
      }
    }
    if (!closed && looks_like_key(lines[n + 1])) return static_cast<int>(n);
  }
  return -1;
}

}  // namespace

YAML::Node LoadYamlText(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    const int quote_line = UnclosedQuoteLine(text);
    if (quote_line >= 0 && (e.mark.line < 0 || quote_line <= e.mark.line)) {
      throw InputError(source + ":" + std::to_string(quote_line + 1),
                       "malformed YAML: the quoted value opened on this line is not closed on "
                       "it (an unclosed quote?); the parser then failed at line " +
                           std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
    throw InputError(YamlWhere(source, e.mark, ""), "malformed YAML: " + e.msg);
  }
  YAML::Mark mark;
  std::string swallowed;
  if (FindRunawayQuote(root, text, &mark, &swallowed)) {
    throw InputError(YamlWhere(source, mark, ""),
                     "malformed YAML: a quoted value opened here runs over the following lines "
                     "and swallows the key '" + swallowed + "': an unclosed quote?");
  }
  return root;
}

void RequireRegularFile(const std::string& path, std::uintmax_t max_bytes) {
  namespace fs = std::filesystem;
  if (path.empty()) throw InputError("''", "expected a file path, got ''");
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) throw InputError(path, "cannot open file (no such file)");
  if (fs::is_directory(st)) throw InputError(path, "cannot read file: it is a folder");
  if (!fs::is_regular_file(st)) {
    throw InputError(path, "cannot read file: not a regular file (a FIFO, socket or device "
                           "could block or never end)");
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path, "cannot read file: " + ec.message());
  if (size > max_bytes) {
    throw InputError(path, "file of " + std::to_string(size) + " bytes is larger than the limit "
                           "of " + std::to_string(max_bytes) + " bytes for this kind of input");
  }
}

std::string ReadTextFile(const std::string& path, std::uintmax_t max_bytes) {
  RequireRegularFile(path, max_bytes);
  NoteInput(path);
  // Opened without blocking (a FIFO swapped in after the check cannot hang the open), checked
  // again on the open descriptor, and read to at most max_bytes whatever the file grows to.
  const int fd = open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, std::string("cannot open file: ") + std::strerror(errno));
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    close(fd);
    throw InputError(path, "cannot read file: not a regular file");
  }
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = read(fd, buf, sizeof(buf));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string why = std::strerror(errno);
      close(fd);
      throw InputError(path, "cannot read file: " + why);
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) {
      close(fd);
      throw InputError(path, "file grew past the limit of " + std::to_string(max_bytes) +
                                 " bytes for this kind of input while it was read");
    }
  }
  close(fd);
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
  const YamlField& angles = rpy ? *rpy : *zyz;
  const Vector3 deg = r.Vector(angles);
  for (int k = 0; k < 3; ++k) {
    if (std::abs(deg(k)) > 360.0) {
      r.Fail(angles.Item(static_cast<std::size_t>(k)),
             "expected an angle within +-360 deg (angles are periodic; a larger value is a unit "
             "mistake), got " + DescribeNode(angles.Item(static_cast<std::size_t>(k)).node));
    }
  }
  const Vector3 rad(DegToRad(deg.x()), DegToRad(deg.y()), DegToRad(deg.z()));
  Transform X = Transform::Identity();
  X.translation() = r.Vector(m.Get("xyz_mm")) / 1000.0;
  X.linear() = rpy ? RpyToRotation(rad) : RotationFromZyz(rad);
  return X;
}

Transform ReadPoseWithin(const YamlReader& r, const YamlField& f, double max_translation_m,
                         const std::string& why) {
  const YamlMap m(r, f, {"xyz_mm", "rpy_deg", "zyz_deg"});
  const Transform X = ReadPose(r, m);
  const double length = X.translation().norm();
  if (length > max_translation_m) {
    std::ostringstream os;
    os << "translation xyz_mm must be at most " << 1e3 * max_translation_m << " mm long (" << why
       << "), got " << 1e3 * length << " mm";
    r.Fail(*m.Find("xyz_mm", true), os.str());
  }
  return X;
}

Matrix3 RpyToRotation(const Vector3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vector3::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Vector3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vector3::UnitX()))
      .toRotationMatrix();
}

}  // namespace twin
