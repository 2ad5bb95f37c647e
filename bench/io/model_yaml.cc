#include "bench/io/model_yaml.h"

#include <charconv>
#include <optional>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "bench/io/plausibility.h"
#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"
#include "calib/common/text_format.h"

namespace twin {
namespace {

using Keys = YamlKeys;
using Field = YamlField;
using Reader = YamlReader;
using MapFields = YamlMap;

const Keys kRootKeys = {"robot"};
const Keys kRobotKeys = {"name", "angle_unit", "base", "links", "tool", "end"};
const Keys kLinkKeys = {"name", "theta_offset", "d", "a", "alpha", "beta",
                        "limits", "mass", "com", "inertia"};
const Keys kToolKeys = {"name", "theta_offset", "d", "a", "alpha", "beta",
                        "mass", "com", "inertia"};
const Keys kTransformKeys = {"xyz", "rpy"};

// The five eq. 2 parameters in file order; angles are scaled by the file's angle unit.
struct DhField {
  const char* key;
  double DhParameters::*member;
  bool is_angle;
};
constexpr DhField kDhFields[] = {
    {"theta_offset", &DhParameters::theta_offset, true},
    {"d", &DhParameters::d, false},
    {"a", &DhParameters::a, false},
    {"alpha", &DhParameters::alpha, true},
    {"beta", &DhParameters::beta, true},
};

constexpr double kRadPerDeg = kPi / 180.0;  // the reader's scale for angle_unit: deg

std::string UnitName(double angle_scale) { return angle_scale == kRadPerDeg ? "deg" : "rad"; }

// Plausibility (bench/io/plausibility.h): each check fails at the field with the limit.
void CheckPlausible(const Reader& r, const Field& f, const std::optional<std::string>& problem) {
  if (problem) r.Fail(f, *problem);
}

double Length(const Reader& r, const Field& f) {
  const double v = r.Number(f);
  CheckPlausible(r, f, plausibility::LengthProblem(v));
  return v;
}

double Angle(const Reader& r, const Field& f, double angle_scale) {
  const double v = r.Number(f) * angle_scale;
  CheckPlausible(r, f, plausibility::AngleProblem(v, UnitName(angle_scale), angle_scale));
  return v;
}

Vector3 Lengths(const Reader& r, const Field& f) {
  const Vector3 v = r.Vector(f);
  for (int k = 0; k < 3; ++k) {
    CheckPlausible(r, f.Item(static_cast<std::size_t>(k)), plausibility::LengthProblem(v(k)));
  }
  return v;
}

// Inertia file order [ixx, iyy, izz, ixy, ixz, iyz] as (row, col) of I_Com.
constexpr std::pair<int, int> kInertiaEntries[] = {{0, 0}, {1, 1}, {2, 2},
                                                   {0, 1}, {0, 2}, {1, 2}};

JointLimits ParseLimits(const Reader& r, const Field& f, double angle_scale) {
  const std::vector<double> v = r.Numbers(f, 2);
  for (std::size_t k = 0; k < 2; ++k) {
    CheckPlausible(r, f.Item(k),
                   plausibility::JointLimitProblem(v[k] * angle_scale, UnitName(angle_scale),
                                                   angle_scale));
  }
  if (!(v[0] < v[1])) {
    std::ostringstream os;
    os << "lower limit " << v[0] << " must be below upper limit " << v[1];
    r.Fail(f, os.str());
  }
  return {v[0] * angle_scale, v[1] * angle_scale};
}

LinkInertia ParseInertia(const Reader& r, const MapFields& m, bool required) {
  LinkInertia in;
  if (const auto f = m.Find("mass", required)) {
    in.mass = r.Number(*f);
    CheckPlausible(r, *f, plausibility::MassProblem(in.mass));
  }
  if (const auto f = m.Find("com", required)) in.p_LiCom = Lengths(r, *f);
  if (const auto f = m.Find("inertia", required)) {
    const std::vector<double> v = r.Numbers(*f, 6);
    for (std::size_t k = 0; k < v.size(); ++k) {
      const auto [i, j] = kInertiaEntries[k];
      in.I_Com(i, j) = in.I_Com(j, i) = v[k];
    }
    CheckPlausible(r, *f, plausibility::InertiaProblem(in.mass, in.I_Com));
  } else if (const auto mass = m.Find("mass", false); mass && in.mass > 0.0) {
    r.Fail(*mass, "a link with mass needs its inertia [ixx, iyy, izz, ixy, ixz, iyz] (kg m^2)");
  }
  return in;
}

Link ParseLink(const Reader& r, const Field& f, double angle_scale, bool is_tool) {
  const MapFields m(r, f, is_tool ? kToolKeys : kLinkKeys);
  Link link;
  link.name = r.String(m.Get("name"));
  for (const DhField& d : kDhFields) {
    const Field v = m.Get(d.key);
    link.dh.*d.member = d.is_angle ? Angle(r, v, angle_scale) : Length(r, v);
  }
  if (!is_tool) link.limits = ParseLimits(r, m.Get("limits"), angle_scale);
  link.inertia = ParseInertia(r, m, !is_tool);
  return link;
}

// Inverse of RpyToRotation. Yaw comes from the first column; roll and pitch are then read
// from Rz(-yaw) R = Ry(p) Rx(r), so the three angles stay consistent even at pitch = +-90 deg
// where yaw alone is ill-conditioned.
Vector3 RotationToRpy(const Matrix3& R) {
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const Matrix3 M = Eigen::AngleAxisd(-yaw, Vector3::UnitZ()).toRotationMatrix() * R;
  const double roll = std::atan2(-M(1, 2), M(1, 1));
  const double pitch = std::atan2(-M(2, 0), M(0, 0));
  return Vector3(roll, pitch, yaw);
}

Transform ParseTransform(const Reader& r, const Field& f, double angle_scale) {
  const MapFields m(r, f, kTransformKeys);
  Transform X = Transform::Identity();
  if (const auto xyz = m.Find("xyz", false)) X.translation() = Lengths(r, *xyz);
  if (const auto rpy = m.Find("rpy", false)) {
    const Vector3 a = r.Vector(*rpy) * angle_scale;
    for (int k = 0; k < 3; ++k) {
      CheckPlausible(r, rpy->Item(static_cast<std::size_t>(k)),
                     plausibility::AngleProblem(a(k), UnitName(angle_scale), angle_scale));
    }
    X.linear() = RpyToRotation(a);
  }
  return X;
}

double ParseAngleScale(const Reader& r, const Field& f) {
  const std::string unit = r.String(f);
  if (unit == "deg") return kRadPerDeg;
  if (unit == "rad") return 1.0;
  r.Fail(f, "angle_unit must be 'deg' or 'rad', got '" + unit + "'");
}

void ParseLinks(const Reader& r, const Field& f, double angle_scale, KinematicModel* model) {
  // One entry per revolute joint, 1 to kMaxJoints of them (six for the papers' arms).
  if (!f.node.IsSequence() || f.node.size() < 1 ||
      f.node.size() > static_cast<std::size_t>(kMaxJoints)) {
    r.Fail(f, "expected a list of 1 to " + std::to_string(kMaxJoints) +
                  " links (one per joint), got " +
                  (f.node.IsSequence() ? std::to_string(f.node.size()) + " entries"
                                       : DescribeNode(f.node)));
  }
  const int n = static_cast<int>(f.node.size());
  const Link tool = model->tool();
  model->links.assign(n + 1, Link{});
  for (int i = 0; i < n; ++i) {
    model->links[i] = ParseLink(r, f.Item(static_cast<std::size_t>(i)), angle_scale, false);
  }
  model->tool() = tool;
}

KinematicModel ParseRobot(const Reader& r, const Field& f) {
  const MapFields m(r, f, kRobotKeys);
  KinematicModel model;
  const Field name = m.Get("name");
  model.name = r.String(name);
  if (model.name.empty()) r.Fail(name, "expected a non-empty robot name");
  const double angle_scale = ParseAngleScale(r, m.Get("angle_unit"));
  ParseLinks(r, m.Get("links"), angle_scale, &model);
  model.tool() = ParseLink(r, m.Get("tool"), angle_scale, true);
  if (const auto base = m.Find("base", false)) {
    model.X_BL0 = ParseTransform(r, *base, angle_scale);
  }
  if (const auto end = m.Find("end", false)) model.X_LtE = ParseTransform(r, *end, angle_scale);
  return model;
}

// ---- Writing ----

std::string Num(double v) { return ShortestNumber(v); }

// Degrees for an angle: the shortest decimal that the reader scales back to exactly rad
// (120, not 119.99999999999999), else the nearest degree value (off by an ulp at most).
std::string Degrees(double rad) {
  for (int digits = 1; digits <= 17; ++digits) {
    char buf[64];
    const auto res = std::to_chars(buf, buf + sizeof(buf), RadToDeg(rad),
                                   std::chars_format::general, digits);
    double deg = 0.0;
    std::from_chars(buf, res.ptr, deg);
    if (deg * kRadPerDeg == rad) return Num(deg);
  }
  return Num(RadToDeg(rad));
}

std::string List(const std::vector<double>& values, std::string (*format)(double) = Num) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : ", ") + format(v);
  return "[" + out + "]";
}


std::string Scalar(const std::string& text) {
  YAML::Emitter e;  // quotes and escapes the text when a plain scalar would not read back
  e << text;
  return e.c_str();
}

using Entries = std::vector<std::pair<std::string, std::string>>;

// Writes "key: value" lines; the first line starts with first_prefix, the rest with indent.
void WriteEntries(std::ostream& os, const Entries& entries, const std::string& first_prefix,
                  const std::string& indent) {
  for (std::size_t i = 0; i < entries.size(); ++i) {
    os << (i == 0 ? first_prefix : indent) << entries[i].first << ": " << entries[i].second
       << "\n";
  }
}

Entries LinkEntries(const Link& link, bool is_tool) {
  Entries e = {{"name", Scalar(link.name)}};
  for (const DhField& d : kDhFields) {
    const double v = link.dh.*d.member;
    e.emplace_back(d.key, d.is_angle ? Degrees(v) : Num(v));
  }
  if (!is_tool) {
    e.emplace_back("limits", List({link.limits.lower, link.limits.upper}, Degrees));
  }
  const LinkInertia& in = link.inertia;
  std::vector<double> inertia;
  for (const auto& [i, j] : kInertiaEntries) inertia.push_back(in.I_Com(i, j));
  e.emplace_back("mass", Num(in.mass));
  e.emplace_back("com", List({in.p_LiCom.x(), in.p_LiCom.y(), in.p_LiCom.z()}));
  e.emplace_back("inertia", List(inertia));
  return e;
}

void WriteTransform(std::ostream& os, const std::string& key, const Transform& X) {
  if (X.matrix() == Eigen::Matrix4d::Identity()) return;
  const Vector3 p = X.translation();
  const Vector3 rpy = RotationToRpy(X.linear());
  os << "  " << key << ":\n"
     << "    xyz: " << List({p.x(), p.y(), p.z()}) << "\n"
     << "    rpy: " << List({rpy.x(), rpy.y(), rpy.z()}, Degrees) << "\n";
}

}  // namespace

KinematicModel ParseModelYaml(const std::string& text, const std::string& source) {
  const YAML::Node root = LoadYamlText(text, source);
  const Reader reader(source);
  const MapFields top(reader, Field{root, ""}, kRootKeys);
  KinematicModel model = ParseRobot(reader, top.Get("robot"));
  ValidateModel(model, source);
  return model;
}

KinematicModel LoadModelYaml(const std::string& path) {
  return ParseModelYaml(ReadTextFile(path), path);
}

std::string ModelToYaml(const KinematicModel& model) {
  std::ostringstream os;
  os << "robot:\n"
     << "  name: " << Scalar(model.name) << "\n"
     << "  angle_unit: deg\n";
  WriteTransform(os, "base", model.X_BL0);
  os << "  links:\n";
  for (int i = 0; i < model.num_joints(); ++i) {
    WriteEntries(os, LinkEntries(model.links[i], false), "    - ", "      ");
  }
  os << "  tool:\n";
  WriteEntries(os, LinkEntries(model.tool(), true), "    ", "    ");
  WriteTransform(os, "end", model.X_LtE);
  return os.str();
}

}  // namespace twin
