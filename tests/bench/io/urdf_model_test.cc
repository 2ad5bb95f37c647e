#include "bench/io/urdf_model.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>
#include <urdf_parser/urdf_parser.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

#include "tests/bench/text_edit.h"

namespace twin {
namespace {

using testing::LineOf;
using testing::Replaced;

// ---- Independent reference: compose urdfdom's parsed joints directly -------------------------

Transform PoseOf(const urdf::Pose& p) {
  const urdf::Rotation& r = p.rotation;
  return Eigen::Translation3d(p.position.x, p.position.y, p.position.z) *
         Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized();
}

urdf::ModelInterfaceSharedPtr MustParse(const std::string& text) {
  urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(text);
  if (!urdf) throw std::runtime_error("test URDF does not parse");
  return urdf;
}

// Names of the non-fixed joints from the root to `tip`, root first.
std::vector<std::string> MovingJointNames(const urdf::ModelInterface& urdf,
                                          const std::string& tip) {
  std::vector<std::string> names;
  for (auto link = urdf.getLink(tip); link->parent_joint;
       link = urdf.getLink(link->parent_joint->parent_link_name)) {
    if (link->parent_joint->type != urdf::Joint::FIXED) names.push_back(link->parent_joint->name);
  }
  std::reverse(names.begin(), names.end());
  return names;
}

// A link's pose in the root frame and whether a moving joint lies between it and the root.
struct RefLink {
  Transform X_RL;
  bool moving;
};

void WalkReference(const urdf::ModelInterface& urdf, const urdf::Link& link, const RefLink& ref,
                   const std::map<std::string, double>& q, std::map<std::string, RefLink>* out) {
  (*out)[link.name] = ref;
  for (const auto& j : link.child_joints) {
    Transform X = ref.X_RL * PoseOf(j->parent_to_joint_origin_transform);
    const auto it = q.find(j->name);
    if (it != q.end()) {
      const Vector3 axis(j->axis.x, j->axis.y, j->axis.z);
      X = X * Eigen::AngleAxisd(it->second, axis.normalized());
    }
    const bool moving = ref.moving || j->type != urdf::Joint::FIXED;
    WalkReference(urdf, *urdf.getLink(j->child_link_name), {X, moving}, q, out);
  }
}

// Every link's pose in the root frame with the chain's moving joints at q (others at zero).
std::map<std::string, RefLink> ReferencePoses(const urdf::ModelInterface& urdf,
                                              const std::string& tip, const JointVector& q) {
  const std::vector<std::string> names = MovingJointNames(urdf, tip);
  std::map<std::string, double> qmap;
  for (size_t i = 0; i < names.size(); ++i) qmap[names[i]] = q(int(i));
  std::map<std::string, RefLink> out;
  WalkReference(urdf, *urdf.getRoot(), {Transform::Identity(), false}, qmap, &out);
  return out;
}

// Whole-body mass, centre of mass and inertia about it, in the base frame.
struct MassTotal {
  double mass = 0.0;
  Vector3 first = Vector3::Zero();
  Matrix3 second = Matrix3::Zero();  // about the base origin

  void Add(double m, const Vector3& c, const Matrix3& R_I_Rt) {
    mass += m;
    first += m * c;
    second += R_I_Rt + m * (c.squaredNorm() * Matrix3::Identity() - c * c.transpose());
  }
  Vector3 Com() const { return first / mass; }
  Matrix3 InertiaAboutCom() const {
    const Vector3 c = Com();
    return second - mass * (c.squaredNorm() * Matrix3::Identity() - c * c.transpose());
  }
};

MassTotal ReferenceMass(const urdf::ModelInterface& urdf, const std::string& tip,
                        const JointVector& q) {
  MassTotal total;
  for (const auto& [name, ref] : ReferencePoses(urdf, tip, q)) {
    const auto in = urdf.getLink(name)->inertial;
    if (!ref.moving || !in) continue;
    const Transform X = ref.X_RL * PoseOf(in->origin);
    Matrix3 I;
    I << in->ixx, in->ixy, in->ixz, in->ixy, in->iyy, in->iyz, in->ixz, in->iyz, in->izz;
    total.Add(in->mass, X.translation(), X.linear() * I * X.linear().transpose());
  }
  return total;
}

MassTotal ModelMass(const KinematicModel& m, const JointVector& q) {
  const FrameSet f = ForwardKinematics(m, q);
  MassTotal total;
  for (int i = 0; i < m.num_links(); ++i) {
    const LinkInertia& in = m.links[i].inertia;
    const Matrix3 R = f.X_BL[i + 1].linear();
    total.Add(in.mass, f.X_BL[i + 1] * in.p_LiCom, R * in.I_Com * R.transpose());
  }
  return total;
}

// Errors between two poses: position [m] and rotation angle [rad].
struct PoseError {
  double position;
  double rotation;
};

PoseError Compare(const Transform& a, const Transform& b) {
  const Eigen::AngleAxisd d(a.linear().transpose() * b.linear());
  return {(a.translation() - b.translation()).norm(), std::abs(d.angle())};
}

JointVector RandomJoints(const KinematicModel& m, std::mt19937& rng) {
  JointVector q(m.num_joints());
  for (int i = 0; i < m.num_joints(); ++i) {
    q(i) = std::uniform_real_distribution<double>(m.links[i].limits.lower,
                                                   m.links[i].limits.upper)(rng);
  }
  return q;
}

// Largest FK and mass-property deviations of a parsed model from the URDF reference.
struct Deviation {
  double position = 0.0, rotation = 0.0, com = 0.0, inertia = 0.0;
};

Deviation CompareWithReference(const std::string& text, const std::string& tip,
                               const KinematicModel& m, int samples, std::mt19937& rng) {
  const auto urdf = MustParse(text);
  Deviation dev;
  for (int s = 0; s < samples; ++s) {
    const JointVector q = RandomJoints(m, rng);
    const PoseError e = Compare(EndPose(m, q), ReferencePoses(*urdf, tip, q).at(tip).X_RL);
    const MassTotal ref = ReferenceMass(*urdf, tip, q), got = ModelMass(m, q);
    dev.position = std::max(dev.position, e.position);
    dev.rotation = std::max(dev.rotation, e.rotation);
    dev.com = std::max(dev.com, (ref.Com() - got.Com()).norm());
    dev.inertia = std::max(dev.inertia, (ref.InertiaAboutCom() - got.InertiaAboutCom()).norm());
  }
  return dev;
}

// ---- URDF text builders -----------------------------------------------------------------------

struct InertialSpec {
  double mass;
  Vector3 xyz, rpy;
  Matrix3 I;
};

struct JointSpec {
  std::string name, type, parent, child;
  Vector3 xyz = Vector3::Zero(), rpy = Vector3::Zero(), axis = Vector3::UnitZ();
  double lower = -2.0, upper = 2.0;
};

std::string Triple(const Vector3& v) {
  std::ostringstream os;
  os.precision(17);
  os << v.x() << ' ' << v.y() << ' ' << v.z();
  return os.str();
}

std::string UrdfText(const std::vector<std::string>& links,
                     const std::map<std::string, InertialSpec>& inertials,
                     const std::vector<JointSpec>& joints) {
  std::ostringstream os;
  os.precision(17);
  os << "<robot name=\"testbot\">\n";
  for (const std::string& l : links) {
    os << "<link name=\"" << l << "\">";
    const auto it = inertials.find(l);
    if (it != inertials.end()) {
      const InertialSpec& in = it->second;
      os << "<inertial><origin xyz=\"" << Triple(in.xyz) << "\" rpy=\"" << Triple(in.rpy)
         << "\"/><mass value=\"" << in.mass << "\"/><inertia ixx=\"" << in.I(0, 0) << "\" ixy=\""
         << in.I(0, 1) << "\" ixz=\"" << in.I(0, 2) << "\" iyy=\"" << in.I(1, 1) << "\" iyz=\""
         << in.I(1, 2) << "\" izz=\"" << in.I(2, 2) << "\"/></inertial>";
    }
    os << "</link>\n";
  }
  for (const JointSpec& j : joints) {
    os << "<joint name=\"" << j.name << "\" type=\"" << j.type << "\"><parent link=\""
       << j.parent << "\"/><child link=\"" << j.child << "\"/><origin xyz=\"" << Triple(j.xyz)
       << "\" rpy=\"" << Triple(j.rpy) << "\"/>";
    if (j.type != "fixed") {
      os << "<axis xyz=\"" << Triple(j.axis) << "\"/><limit lower=\"" << j.lower
         << "\" upper=\"" << j.upper << "\" effort=\"10\" velocity=\"1\"/>";
    }
    os << "</joint>\n";
  }
  os << "</robot>\n";
  return os.str();
}

// A chain base_link - l1 - ... - l<n> whose joints j1..j<n> have the given types, each offset
// 0.1 m along x and turning about alternating z and y axes.
std::string SimpleChain(const std::vector<std::string>& types) {
  std::vector<std::string> links = {"base_link"};
  std::vector<JointSpec> joints;
  for (size_t i = 0; i < types.size(); ++i) {
    links.push_back("l" + std::to_string(i + 1));
    JointSpec j{"j" + std::to_string(i + 1), types[i], links[i], links[i + 1]};
    j.xyz = Vector3(0.1, 0.0, 0.05);
    j.axis = i % 2 ? Vector3::UnitY() : Vector3::UnitZ();
    joints.push_back(j);
  }
  return UrdfText(links, {}, joints);
}

// A UR5-like arm as published in ur_description (rpy joint origins, y and z axes, parallel
// shoulder/elbow/wrist-1 axes), with tool0 as the single leaf.
const char* const kUr5Like = R"(<robot name="ur5_like">
  <link name="base_link"><inertial><mass value="4.0"/><origin xyz="0 0 0"/>
    <inertia ixx="0.0044" ixy="0" ixz="0" iyy="0.0044" iyz="0" izz="0.0072"/></inertial></link>
  <link name="shoulder_link"><inertial><mass value="3.7"/><origin xyz="0 0 0"/>
    <inertia ixx="0.010267" ixy="0" ixz="0" iyy="0.010267" iyz="0" izz="0.00666"/></inertial></link>
  <link name="upper_arm_link"><inertial><mass value="8.393"/><origin xyz="0 0 0.28"/>
    <inertia ixx="0.22689" ixy="0" ixz="0" iyy="0.22689" iyz="0" izz="0.0151074"/></inertial></link>
  <link name="forearm_link"><inertial><mass value="2.275"/><origin xyz="0 0 0.25"/>
    <inertia ixx="0.049443" ixy="0" ixz="0" iyy="0.049443" iyz="0" izz="0.004095"/>
    </inertial></link>
  <link name="wrist_1_link"><inertial><mass value="1.219"/><origin xyz="0 0 0" rpy="0.3 0 0"/>
    <inertia ixx="0.0021942" ixy="0" ixz="0" iyy="0.0021942" iyz="0" izz="0.0021942"/>
    </inertial></link>
  <link name="wrist_2_link"><inertial><mass value="1.219"/><origin xyz="0.01 0 0"/>
    <inertia ixx="0.0021942" ixy="0" ixz="0" iyy="0.0021942" iyz="0" izz="0.0021942"/>
    </inertial></link>
  <link name="wrist_3_link"><inertial><mass value="0.1879"/><origin xyz="0 0.01 0"/>
    <inertia ixx="0.000132" ixy="0" ixz="0" iyy="0.000132" iyz="0" izz="0.000192"/>
    </inertial></link>
  <link name="tool0"><inertial><mass value="0.5"/><origin xyz="0 0 0.03"/>
    <inertia ixx="0.001" ixy="0.0001" ixz="0" iyy="0.001" iyz="0" izz="0.0015"/></inertial></link>
  <joint name="shoulder_pan_joint" type="continuous">
    <parent link="base_link"/><child link="shoulder_link"/>
    <origin xyz="0 0 0.089159" rpy="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="shoulder_lift_joint" type="revolute">
    <parent link="shoulder_link"/><child link="upper_arm_link"/>
    <origin xyz="0 0.13585 0" rpy="0 1.570796325 0"/><axis xyz="0 1 0"/>
    <limit lower="-6.28318530718" upper="6.28318530718" effort="150" velocity="3.15"/></joint>
  <joint name="elbow_joint" type="revolute">
    <parent link="upper_arm_link"/><child link="forearm_link"/>
    <origin xyz="0 -0.1197 0.425" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3.14159265359" upper="3.14159265359" effort="150" velocity="3.15"/></joint>
  <joint name="wrist_1_joint" type="revolute">
    <parent link="forearm_link"/><child link="wrist_1_link"/>
    <origin xyz="0 0 0.39225" rpy="0 1.570796325 0"/><axis xyz="0 1 0"/>
    <limit lower="-6.28318530718" upper="6.28318530718" effort="28" velocity="3.2"/></joint>
  <joint name="wrist_2_joint" type="revolute">
    <parent link="wrist_1_link"/><child link="wrist_2_link"/>
    <origin xyz="0 0.093 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-6.28318530718" upper="6.28318530718" effort="28" velocity="3.2"/></joint>
  <joint name="wrist_3_joint" type="revolute">
    <parent link="wrist_2_link"/><child link="wrist_3_link"/>
    <origin xyz="0 0 0.09465" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-6.28318530718" upper="6.28318530718" effort="28" velocity="3.2"/></joint>
  <joint name="tool0_fixed_joint" type="fixed">
    <parent link="wrist_3_link"/><child link="tool0"/>
    <origin xyz="0 0.0823 0" rpy="-1.570796325 0 0"/></joint>
</robot>)";

// A random unit axis: half the time a signed coordinate axis (e.g. 0 0 -1), else uniform.
Vector3 RandomAxis(std::mt19937& rng) {
  std::uniform_int_distribution<int> pick(0, 5);
  if (std::uniform_int_distribution<int>(0, 1)(rng)) {
    const int k = pick(rng);
    return (k < 3 ? 1.0 : -1.0) * Vector3::Unit(k % 3);
  }
  std::normal_distribution<double> n;
  return Vector3(n(rng), n(rng), n(rng)).normalized();
}

InertialSpec RandomInertial(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), moment(0.05, 0.1);
  const Matrix3 R = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().matrix();
  // Principal moments in [0.05, 0.1] always satisfy the triangle inequality.
  const Matrix3 D = Vector3(moment(rng), moment(rng), moment(rng)).asDiagonal();
  return {0.5 + 4.5 * 0.5 * (u(rng) + 1.0), 0.2 * Vector3(u(rng), u(rng), u(rng)),
          3.0 * Vector3(u(rng), u(rng), u(rng)), R * D * R.transpose()};
}

// An arm of `n` revolute joints (6 by default) in an arbitrary convention: random origins and
// axes, fixed joints at the base, after joints 2 and 4 and two at the tip, continuous joints,
// and a fixed side branch on l3 (so tip_link must be given: "tool0").
std::string RandomArm(std::mt19937& rng, int n = 6) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::pair<std::string, bool>> seq = {{"mount", false}};
  for (int i = 1; i <= n; ++i) {
    seq.push_back({"j" + std::to_string(i), true});
    if (i == 2) seq.push_back({"mid_a", false});
    if (i == 4) seq.push_back({"mid_b", false});
  }
  seq.push_back({"flange_joint", false});
  seq.push_back({"tool0_joint", false});
  std::vector<std::string> links = {"base_link"};
  std::map<std::string, InertialSpec> inertials;
  std::vector<JointSpec> joints;
  for (const auto& [name, moving] : seq) {
    const std::string child = name == "tool0_joint" ? "tool0" : "after_" + name;
    JointSpec j{name, "fixed", links.back(), child};
    j.xyz = 0.3 * Vector3(u(rng), u(rng), u(rng));
    j.rpy = kPi * Vector3(u(rng), u(rng), u(rng));
    if (moving) {
      j.type = u(rng) > 0.3 ? "revolute" : "continuous";
      j.axis = RandomAxis(rng);
      j.lower = -0.5 - 2.5 * std::abs(u(rng));
      j.upper = 0.5 + 2.5 * std::abs(u(rng));
    }
    joints.push_back(j);
    links.push_back(child);
  }
  for (const std::string& l : links) {
    if (u(rng) > -0.6) inertials[l] = RandomInertial(rng);
  }
  JointSpec side{"sensor_joint", "fixed", "after_j3", "sensor"};
  side.xyz = Vector3(0.05, -0.1, 0.2);
  side.rpy = Vector3(0.4, -1.1, 2.0);
  joints.push_back(side);
  links.push_back("sensor");
  inertials["sensor"] = RandomInertial(rng);
  return UrdfText(links, inertials, joints);
}

// ---- A model built in code, resembling a 6-DOF industrial arm ---------------------------------

KinematicModel IndustrialArm() {
  KinematicModel m;
  m.name = "arm";
  struct Row { double th, d, a, al, lo, hi, mass; };
  const Row rows[7] = {{0, 0.1365, 0.100, 90, -170, 170, 4.0},
                               {90, 0, 0.290, 0, -120, 120, 3.0},
                               {0, 0, 0.121, 90, -140, 140, 2.0},
                               {0, 0.310, 0, -90, -180, 180, 1.5},
                               {-90, 0, 0, 90, -120, 120, 1.0},
                               {0, 0.1215, 0, 0, -270, 270, 0.5},
                               {-90, 0.02, 0.060, 10, 0, 0, 0.3}};
  for (int i = 0; i < 7; ++i) {
    Link& l = m.links[i];
    const Row& r = rows[i];
    l.name = i < 6 ? "link" + std::to_string(i + 1) : "tool";
    l.dh = {DegToRad(r.th), r.d, r.a, DegToRad(r.al), 0.0};
    l.limits = {DegToRad(r.lo), DegToRad(r.hi)};
    const Matrix3 R = Eigen::AngleAxisd(0.3 * i, Vector3(1, 2, 3).normalized()).matrix();
    const Vector3 moments(0.03 + 0.003 * i, 0.03, 0.028);  // triangle inequality holds
    l.inertia = {r.mass, Vector3(0.01 * i, -0.02, 0.05), R * moments.asDiagonal() * R.transpose()};
  }
  m.links[1].dh.beta = 0.001;  // Hayati angle: axes 2 and 3 nearly parallel
  m.X_BL0 = Eigen::Translation3d(0.5, -0.2, 0.1) *
            Eigen::AngleAxisd(0.3, Vector3(1, -1, 2).normalized());
  m.X_LtE = Eigen::Translation3d(0.01, 0.02, 0.08) *
            Eigen::AngleAxisd(-2.0, Vector3(0, 1, 1).normalized());
  return m;
}

std::string Sci(double v) {
  std::ostringstream os;
  os << std::scientific << std::setprecision(2) << v;
  return os.str();
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}


// Tolerances: every comparison below is between two exact descriptions of the same rigid chain,
// so the only differences are double rounding over ~20 composed transforms (~1e-15) and, for
// exported URDF text, 17-digit decimal round trips (exact) and rpy/quaternion conversion
// (~1e-16). 1e-9 m / 1e-9 rad leaves six orders of margin and is still ~1000x below any
// calibration effect (micrometres).
constexpr double kPosTol = 1e-9;  // [m]
constexpr double kRotTol = 1e-9;  // [rad]
constexpr double kInertiaTol = 1e-9;  // [kg m^2], moments here are 0.001..10

TEST(UrdfModel, Ur5LikeArmMatchesReferenceFk) {
  const KinematicModel m = ParseUrdf(kUr5Like, "ur5_like.urdf");
  std::mt19937 rng(1);
  const Deviation dev = CompareWithReference(kUr5Like, "tool0", m, 300, rng);
  EXPECT_LT(dev.position, kPosTol);
  EXPECT_LT(dev.rotation, kRotTol);
  EXPECT_LT(dev.com, kPosTol);
  EXPECT_LT(dev.inertia, kInertiaTol);
  RecordProperty("max_position_error", Sci(dev.position));
  RecordProperty("max_rotation_error", Sci(dev.rotation));
  RecordProperty("max_com_error", Sci(dev.com));
}

TEST(UrdfModel, Ur5LikeArmGetsItsPublishedDhLengths) {
  const KinematicModel m = ParseUrdf(kUr5Like, "ur5_like.urdf");
  // Pure geometry of decimal inputs: only rounding (1e-15) separates these from the book values.
  constexpr double kTol = 1e-12;
  EXPECT_NEAR(m.links[0].dh.d, 0.089159, kTol);
  EXPECT_NEAR(std::abs(m.links[1].dh.a), 0.425, kTol);
  EXPECT_NEAR(std::abs(m.links[2].dh.a), 0.39225, kTol);
  EXPECT_NEAR(std::abs(m.links[3].dh.d), 0.10915, kTol);
  EXPECT_NEAR(std::abs(m.links[4].dh.d), 0.09465, kTol);
  EXPECT_NEAR(m.links[5].dh.d, 0.0823, kTol);
  // Parallel shoulder, elbow and wrist-1 axes: common normal in the previous x-y plane.
  for (int i : {1, 2}) {
    EXPECT_NEAR(m.links[i].dh.d, 0.0, kTol) << i;
    EXPECT_NEAR(m.links[i].dh.beta, 0.0, kTol) << i;
  }
  EXPECT_TRUE(m.X_BL0.isApprox(Transform::Identity(), kTol));  // base z is axis 1
}

TEST(UrdfModel, Ur5LikeArmNamesLimitsAndMasses) {
  UrdfImportOptions opt;
  opt.robot_name = "r2";
  const KinematicModel m = ParseUrdf(kUr5Like, "ur5_like.urdf", opt);
  EXPECT_EQ(m.name, "r2");
  EXPECT_EQ(ParseUrdf(kUr5Like, "ur5_like.urdf").name, "ur5_like");
  for (int i = 0; i < 6; ++i) EXPECT_EQ(m.links[i].name, "link" + std::to_string(i + 1));
  EXPECT_EQ(m.tool().name, "tool");
  // Continuous shoulder pan gets +-2 pi; the elbow keeps its URDF limits (exact decimals).
  EXPECT_DOUBLE_EQ(m.links[0].limits.upper, 2.0 * kPi);
  EXPECT_DOUBLE_EQ(m.links[2].limits.lower, -3.14159265359);
  // Base mass is not modelled; tool0 rides on joint 6 and merges into link 6; sums of a few
  // decimals, so 1e-12 kg covers rounding.
  EXPECT_NEAR(m.links[0].inertia.mass, 3.7, 1e-12);
  EXPECT_NEAR(m.links[5].inertia.mass, 0.1879 + 0.5, 1e-12);
  EXPECT_EQ(m.tool().inertia.mass, 0.0);
}

TEST(UrdfModel, RoundTripPreservesPoseAndMassProperties) {
  const KinematicModel m = IndustrialArm();
  const std::string text = ModelToUrdf(m);
  const KinematicModel back = ParseUrdf(text, "roundtrip.urdf");
  EXPECT_EQ(back.name, "arm");
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(back.links[i].limits.lower, m.links[i].limits.lower, 1e-15);  // 17 digits: exact
    EXPECT_NEAR(back.links[i].limits.upper, m.links[i].limits.upper, 1e-15);
  }
  // Links 1..5 keep their mass; the tool body rides on joint 6 and merges into link 6.
  for (int i = 0; i < 6 - 1; ++i) {
    EXPECT_NEAR(back.links[i].inertia.mass, m.links[i].inertia.mass, 1e-12) << i;
  }
  EXPECT_NEAR(back.links[5].inertia.mass, m.links[5].inertia.mass + m.tool().inertia.mass, 1e-12);
  EXPECT_EQ(back.tool().inertia.mass, 0.0);

  std::mt19937 rng(2);
  double max_pos = 0.0, max_rot = 0.0, max_com = 0.0, max_inertia = 0.0;
  for (int s = 0; s < 300; ++s) {
    const JointVector q = RandomJoints(m, rng);
    const PoseError e = Compare(EndPose(back, q), EndPose(m, q));
    const MassTotal a = ModelMass(m, q), b = ModelMass(back, q);
    max_pos = std::max(max_pos, e.position);
    max_rot = std::max(max_rot, e.rotation);
    max_com = std::max(max_com, (a.Com() - b.Com()).norm());
    max_inertia = std::max(max_inertia, (a.InertiaAboutCom() - b.InertiaAboutCom()).norm());
  }
  EXPECT_LT(max_pos, kPosTol);
  EXPECT_LT(max_rot, kRotTol);
  EXPECT_LT(max_com, kPosTol);
  EXPECT_LT(max_inertia, kInertiaTol);
  RecordProperty("max_position_error", Sci(max_pos));
  RecordProperty("max_rotation_error", Sci(max_rot));
  RecordProperty("max_com_error", Sci(max_com));

  // The exported text itself, composed by the reference, also equals the model.
  const Deviation dev = CompareWithReference(text, "end", m, 100, rng);
  EXPECT_LT(dev.position, kPosTol);
  EXPECT_LT(dev.rotation, kRotTol);
  EXPECT_LT(dev.com, kPosTol);
}

TEST(UrdfModel, ExportKeepsRotationsAtGimbalLock) {
  // URDF rpy is singular at pitch +-90 deg; the exported text must still be exact there.
  std::mt19937 rng(5);
  for (double pitch : {kPi / 2, -kPi / 2, kPi / 2 - 1e-9, -kPi / 2 + 1e-7, kPi / 2 + 1e-12}) {
    KinematicModel m = IndustrialArm();
    const Matrix3 R = (Eigen::AngleAxisd(0.7, Vector3::UnitZ()) *
                       Eigen::AngleAxisd(pitch, Vector3::UnitY()) *
                       Eigen::AngleAxisd(-1.2, Vector3::UnitX())).matrix();
    m.X_BL0.linear() = R;
    m.X_LtE.linear() = R.transpose();
    const Deviation dev = CompareWithReference(ModelToUrdf(m), "end", m, 50, rng);
    EXPECT_LT(dev.position, kPosTol) << pitch;
    EXPECT_LT(dev.rotation, kRotTol) << pitch;
  }
}

TEST(UrdfModel, RandomConventionArmsMatchReferenceFk) {
  std::mt19937 rng(3);
  UrdfImportOptions opt;
  opt.tip_link = "tool0";  // the sensor side branch is a second leaf
  Deviation worst;
  for (int arm = 0; arm < 40; ++arm) {
    const std::string text = RandomArm(rng);
    const KinematicModel m = ParseUrdf(text, "random.urdf", opt);
    const Deviation dev = CompareWithReference(text, "tool0", m, 50, rng);
    worst.position = std::max(worst.position, dev.position);
    worst.rotation = std::max(worst.rotation, dev.rotation);
    worst.com = std::max(worst.com, dev.com);
    worst.inertia = std::max(worst.inertia, dev.inertia);
  }
  EXPECT_LT(worst.position, kPosTol);
  EXPECT_LT(worst.rotation, kRotTol);
  EXPECT_LT(worst.com, kPosTol);
  EXPECT_LT(worst.inertia, kInertiaTol);
  RecordProperty("max_position_error", Sci(worst.position));
  RecordProperty("max_rotation_error", Sci(worst.rotation));
  RecordProperty("max_com_error", Sci(worst.com));
}

TEST(UrdfModel, RandomSevenJointArmsMatchReferenceFk) {
  // Redundant arms (7 revolute joints, e.g. a KUKA iiwa or a Franka Panda): the same import,
  // the same tolerances (kPosTol: double rounding over ~20 transforms).
  std::mt19937 rng(4);
  UrdfImportOptions opt;
  opt.tip_link = "tool0";
  Deviation worst;
  for (int arm = 0; arm < 20; ++arm) {
    const std::string text = RandomArm(rng, 7);
    const KinematicModel m = ParseUrdf(text, "random7.urdf", opt);
    ASSERT_EQ(m.num_joints(), 7);
    ASSERT_EQ(m.num_parameters(), 40);
    const Deviation dev = CompareWithReference(text, "tool0", m, 50, rng);
    worst.position = std::max(worst.position, dev.position);
    worst.rotation = std::max(worst.rotation, dev.rotation);
    worst.com = std::max(worst.com, dev.com);
  }
  EXPECT_LT(worst.position, kPosTol);
  EXPECT_LT(worst.rotation, kRotTol);
  EXPECT_LT(worst.com, kPosTol);
  RecordProperty("max_position_error", Sci(worst.position));
}

TEST(UrdfModel, NearlyParallelAxesMatchReferenceFk) {
  // Tilt the elbow axis away from the shoulder-lift axis by angles around the switch from
  // classic DH to the Hayati form (sine 1e-2) and down to exactly parallel.
  const std::string from = R"(<origin xyz="0 -0.1197 0.425" rpy="0 0 0"/>)";
  const size_t at = std::string(kUr5Like).find(from);
  ASSERT_NE(at, std::string::npos);
  std::mt19937 rng(4);
  for (double tilt : {0.0, 1e-12, 1e-6, 1e-3, 0.00999, 0.01001, 0.1, -0.3}) {
    std::ostringstream origin;
    origin.precision(17);
    origin << R"(<origin xyz="0 -0.1197 0.425" rpy="0 0 )" << tilt << R"("/>)";
    const std::string text = std::string(kUr5Like).replace(at, from.size(), origin.str());
    const KinematicModel m = ParseUrdf(text, "tilted.urdf");
    const Deviation dev = CompareWithReference(text, "tool0", m, 100, rng);
    EXPECT_LT(dev.position, kPosTol) << tilt;
    EXPECT_LT(dev.rotation, kRotTol) << tilt;
    EXPECT_LT(dev.com, kPosTol) << tilt;
    // Lengths stay arm-sized in both forms (no far-away common normal).
    EXPECT_LT(std::abs(m.links[1].dh.d), 0.5) << tilt;
  }
}

TEST(UrdfModel, LoadUrdfReadsAFile) {
  const std::string path = ::testing::TempDir() + "urdf_model_test_ur5.urdf";
  std::ofstream(path) << kUr5Like;
  const KinematicModel m = LoadUrdf(path);
  const JointVector q = JointVector::Constant(6, 0.3);
  const PoseError e = Compare(EndPose(m, q), EndPose(ParseUrdf(kUr5Like, "x"), q));
  EXPECT_EQ(e.position, 0.0);  // same text, same deterministic computation
  EXPECT_EQ(e.rotation, 0.0);
}

TEST(UrdfModel, FiveRevoluteJointsMakeAFiveJointChain) {
  const KinematicModel m =
      ParseUrdf(SimpleChain(std::vector<std::string>(5, "revolute")), "five.urdf");
  EXPECT_EQ(m.num_joints(), 5);
}

TEST(UrdfModelErrors, WrongJointCountIsNamed) {
  const std::string msg = ErrorOf([] {
    ParseUrdf(SimpleChain(std::vector<std::string>(13, "revolute")), "thirteen.urdf");
  });
  EXPECT_NE(msg.find("thirteen.urdf"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 1 to 12 revolute joints between 'base_link' and 'l13', found 13"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("[j1, j2, j3, j4, j5, j6, j7, j8, j9, j10, j11, j12, j13]"),
            std::string::npos) << msg;
}

TEST(UrdfModelErrors, PrismaticJointIsNamed) {
  const std::string msg = ErrorOf([] {
    ParseUrdf(SimpleChain({"revolute", "revolute", "prismatic", "revolute", "revolute",
                           "revolute", "revolute"}),
              "slide.urdf");
  });
  EXPECT_NE(msg.find("'j3'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("prismatic"), std::string::npos) << msg;
}

TEST(UrdfModelErrors, MalformedXmlNamesSource) {
  const std::string msg =
      ErrorOf([] { ParseUrdf("<robot name=\"x\"><link name=\"a\">", "broken.urdf"); });
  EXPECT_NE(msg.find("broken.urdf"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a valid URDF"), std::string::npos) << msg;
}

// A six-joint chain base_link - l1 - ... - l6 with fixed frame-only leaves {name, parent link}.
std::string ChainWithLeaves(const std::vector<std::pair<std::string, std::string>>& leaves) {
  std::vector<std::string> links = {"base_link"};
  std::vector<JointSpec> joints;
  for (int i = 1; i <= 6; ++i) {
    links.push_back("l" + std::to_string(i));
    JointSpec j{"j" + std::to_string(i), "revolute", links[i - 1], links[i]};
    j.xyz = Vector3(0.1, 0.0, 0.05);
    j.axis = i % 2 ? Vector3::UnitZ() : Vector3::UnitY();
    joints.push_back(j);
  }
  for (const auto& [name, on] : leaves) {
    links.push_back(name);
    joints.push_back(JointSpec{name + "_joint", "fixed", on, name});
  }
  return UrdfText(links, {}, joints);
}

TEST(UrdfModelErrors, TwoLeavesWithAsManyMovingJointsNeedTipLink) {
  // camera and tool0 both end the arm.
  const std::string text = ChainWithLeaves({{"camera", "l6"}, {"tool0", "l6"}});
  const std::string msg = ErrorOf([&] { ParseUrdf(text, "leaves.urdf"); });
  EXPECT_NE(msg.find("camera"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tip_link"), std::string::npos) << msg;
  UrdfImportOptions opt;
  EXPECT_NE(msg.find("tool0"), std::string::npos) << msg;
  opt.tip_link = "tool0";
  EXPECT_NO_THROW(ParseUrdf(text, "leaves.urdf", opt));
  opt.tip_link = "camera";
  EXPECT_NO_THROW(ParseUrdf(text, "leaves.urdf", opt));
  opt.tip_link = "nope";
  EXPECT_NE(ErrorOf([&] { ParseUrdf(text, "leaves.urdf", opt); }).find("tip_link 'nope'"),
            std::string::npos);
}

TEST(UrdfModel, ALeafNearerTheBaseIsPassedOverWithAWarning) {
  // A sensor frame on link 4 is not the end of the arm: l6 has more moving joints above it.
  const std::string text = ChainWithLeaves({{"camera", "l4"}});
  std::vector<std::string> warnings;
  const KinematicModel m = ParseUrdf(text, "leaves.urdf", {}, &warnings);
  UrdfImportOptions opt;
  opt.tip_link = "l6";
  const KinematicModel explicit_tip = ParseUrdf(text, "leaves.urdf", opt);
  std::mt19937 rng(3);
  const JointVector q = RandomJoints(m, rng);
  // Same parse of the same chain: bit-identical poses are expected; 1e-12 m allows nothing
  // but rounding.
  EXPECT_LT(Compare(EndPose(m, q), EndPose(explicit_tip, q)).position, 1e-12);
  bool named = false;
  for (const std::string& w : warnings) {
    named |= w.find("chose 'l6'") != std::string::npos &&
             w.find("camera (4 moving joints)") != std::string::npos &&
             w.find("leaves.urdf") != std::string::npos;
  }
  EXPECT_TRUE(named) << ::testing::PrintToString(warnings);
}

// kUr5Like as ROS-Industrial support packages write arms: a frame-only `base` link beside
// base_link (the robot controller's base frame), and mesh visuals.
std::string RosIndustrialLike(const std::string& mesh) {
  std::string text = Replaced(kUr5Like, "<link name=\"tool0\">",
                              "<link name=\"base\"/>\n  <joint name=\"base_link-base\" "
                              "type=\"fixed\"><parent link=\"base_link\"/><child "
                              "link=\"base\"/><origin xyz=\"0 0 0\" rpy=\"0 0 3.14159265\"/>"
                              "</joint>\n  <link name=\"tool0\">");
  return Replaced(text, "<link name=\"shoulder_link\">",
                  "<link name=\"shoulder_link\"><visual><geometry><mesh filename=\"" + mesh +
                      "\"/></geometry></visual>");
}

TEST(UrdfModel, RosIndustrialBaseFrameLeafLoadsWithoutTipLink) {
  const std::string text = RosIndustrialLike("package://no_such_support/meshes/link_1.stl");
  std::vector<std::string> warnings;
  const KinematicModel m = ParseUrdf(text, "ros_i.urdf", {}, &warnings);
  std::mt19937 rng(5);
  // The independent reference (urdfdom's joints composed directly) to tool0.
  const Deviation dev = CompareWithReference(text, "tool0", m, 50, rng);
  EXPECT_LT(dev.position, kPosTol);
  EXPECT_LT(dev.rotation, kRotTol);
  bool chose = false, mesh = false;
  for (const std::string& w : warnings) {
    chose |= w.find("chose 'tool0'") != std::string::npos &&
             w.find("base (0 moving joints)") != std::string::npos;
    mesh |= w.find("1 of 1 mesh files cannot be resolved") != std::string::npos &&
            w.find("shoulder_link: package://no_such_support/meshes/link_1.stl") !=
                std::string::npos &&
            w.find("capsules") != std::string::npos;
  }
  EXPECT_TRUE(chose) << ::testing::PrintToString(warnings);
  EXPECT_TRUE(mesh) << ::testing::PrintToString(warnings);
  // kUr5Like has every <inertial>: no mass warning.
  for (const std::string& w : warnings) EXPECT_EQ(w.find("<inertial>"), std::string::npos) << w;
  // The URDF joint names stay with the model (messages name them).
  EXPECT_EQ(m.links[1].joint_name, "shoulder_lift_joint");
}

TEST(UrdfModel, BaseLinkStartsTheChainThere) {
  // A `world` root with base_link 0.5 m up and turned: from base_link the arm's pose is the
  // world one seen from base_link.
  std::string text = Replaced(kUr5Like, "<link name=\"base_link\">",
                              "<link name=\"world\"/>\n  <joint name=\"world_joint\" "
                              "type=\"fixed\"><parent link=\"world\"/><child "
                              "link=\"base_link\"/><origin xyz=\"0.1 0 0.5\" rpy=\"0 0 0.7\"/>"
                              "</joint>\n  <link name=\"base_link\">");
  const KinematicModel from_world = ParseUrdf(text, "world.urdf");
  UrdfImportOptions opt;
  opt.base_link = "base_link";
  const KinematicModel from_base = ParseUrdf(text, "world.urdf", opt);
  Transform X_WB = Transform::Identity();
  X_WB.translation() = Vector3(0.1, 0.0, 0.5);
  X_WB.linear() = Eigen::AngleAxisd(0.7, Vector3::UnitZ()).matrix();
  std::mt19937 rng(7);
  for (int k = 0; k < 20; ++k) {
    const JointVector q = RandomJoints(from_base, rng);
    const PoseError e = Compare(X_WB * EndPose(from_base, q), EndPose(from_world, q));
    EXPECT_LT(e.position, kPosTol);
    EXPECT_LT(e.rotation, kRotTol);
  }
  opt.base_link = "tool0";  // below the tip: no chain
  EXPECT_NE(ErrorOf([&] { ParseUrdf(text, "world.urdf", opt); }).find("base_link 'tool0'"),
            std::string::npos);
}

TEST(UrdfModel, MeshesThatResolveGiveNoMeshWarning) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("urdf_mesh_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "link_1.stl") << "solid x\nendsolid x\n";
  const std::string path = (dir / "arm.urdf").string();
  std::ofstream(path) << RosIndustrialLike("meshes/link_1.stl");  // relative to the URDF
  std::vector<std::string> warnings;
  LoadUrdf(path, {}, &warnings);
  for (const std::string& w : warnings) {
    EXPECT_EQ(w.find("cannot be resolved"), std::string::npos) << w;
  }
  // The same file under another folder: the relative mesh no longer resolves.
  const std::filesystem::path other = dir / "elsewhere";
  std::filesystem::create_directories(other);
  std::filesystem::copy_file(path, other / "arm.urdf");
  warnings.clear();
  LoadUrdf((other / "arm.urdf").string(), {}, &warnings);
  bool mesh = false;
  for (const std::string& w : warnings) mesh |= w.find("cannot be resolved") != std::string::npos;
  EXPECT_TRUE(mesh) << ::testing::PrintToString(warnings);
  std::filesystem::remove_all(dir);
}

TEST(UrdfModel, MissingInertialsAreNamedWithTheStandIn) {
  std::vector<std::string> warnings;
  ParseUrdf(SimpleChain({"revolute", "revolute", "revolute", "revolute", "revolute", "revolute"}),
            "massless.urdf", {}, &warnings);
  bool named = false;
  for (const std::string& w : warnings) {
    named |= w.find("massless.urdf") != std::string::npos &&
             w.find("[j1, j2, j3, j4, j5, j6]") != std::string::npos &&
             w.find("0.1 kg") != std::string::npos;
  }
  EXPECT_TRUE(named) << ::testing::PrintToString(warnings);
}

TEST(UrdfModelErrors, MissingFileNamesPath) {
  const std::string path = "/nonexistent_dir/arm.urdf";
  const std::string msg = ErrorOf([&] { LoadUrdf(path); });
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
}

TEST(UrdfModelErrors, CoincidentAndZeroAxesAreNamed) {
  std::vector<std::string> links = {"base_link"};
  std::vector<JointSpec> joints;
  for (int i = 1; i <= 6; ++i) {
    links.push_back("l" + std::to_string(i));
    JointSpec j{"j" + std::to_string(i), "revolute", links[i - 1], links[i]};
    j.xyz = Vector3(0.1, 0.0, 0.05);
    j.axis = i % 2 ? Vector3::UnitZ() : Vector3::UnitY();
    joints.push_back(j);
  }
  joints[3].xyz = Vector3(0.0, 0.0, 0.2);  // j4 on the line of j3's z axis
  joints[3].axis = -Vector3::UnitZ();
  const std::string coincident = ErrorOf([&] { ParseUrdf(UrdfText(links, {}, joints), "c.urdf"); });
  EXPECT_NE(coincident.find("'j3' and 'j4'"), std::string::npos) << coincident;
  EXPECT_NE(coincident.find("coincident"), std::string::npos) << coincident;
  joints[3].axis = Vector3::UnitY();
  joints[4].axis = Vector3::Zero();
  const std::string zero = ErrorOf([&] { ParseUrdf(UrdfText(links, {}, joints), "z.urdf"); });
  EXPECT_NE(zero.find("'j5' has a zero axis"), std::string::npos) << zero;
}

// Plausibility (bench/io/plausibility.h): URDFs get the checks of YAML models, at the element's
// line, and urdfdom's own reason when it refuses or drops an element.
TEST(UrdfModelErrors, AbsurdValuesAreRefusedAtTheElementWithTheLimit) {
  const std::string ur5 = kUr5Like;
  struct Case {
    std::string from, to, where, expected;
  };
  const Case cases[] = {
      {"<mass value=\"3.7\"/>", "<mass value=\"-3.7\"/>", "link 'shoulder_link' <mass value>",
       "[0, 10000] kg"},
      {"<mass value=\"3.7\"/>", "<mass value=\"1e9\"/>", "link 'shoulder_link' <mass value>",
       "[0, 10000] kg"},
      {"<mass value=\"3.7\"/>", "<mass value=\"nan\"/>", "Link [shoulder_link]",
       "urdfdom: Inertial: mass [nan] is not a float"},
      {"<mass value=\"3.7\"/>", "<mass value=\"heavy\"/>", "Link [shoulder_link]",
       "urdfdom: Inertial: mass [heavy] is not a float"},
      {"ixx=\"0.010267\"", "ixx=\"-5\"", "link 'shoulder_link' <inertia>", "not physical"},
  };
  for (const Case& c : cases) {
    const std::string text = Replaced(ur5, c.from, c.to);
    const std::string msg = ErrorOf([&] { ParseUrdf(text, "arm.urdf"); });
    const std::string at =
        "arm.urdf:" + std::to_string(LineOf(text, "<link name=\"shoulder_link\""));
    EXPECT_TRUE(msg.find(at + " ") != std::string::npos || msg.find(at + ":") != std::string::npos)
        << msg;
    EXPECT_NE(msg.find(c.where), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << msg;
  }
  // Joint origins and limits: a 1000 km offset, a limit of 100 turns.
  std::vector<std::string> links = {"base_link"};
  std::vector<JointSpec> joints;
  for (int i = 1; i <= 6; ++i) {
    links.push_back("l" + std::to_string(i));
    JointSpec j{"j" + std::to_string(i), "revolute", links[i - 1], links[i]};
    j.xyz = Vector3(0.1, 0.0, 0.05);
    j.axis = i % 2 ? Vector3::UnitZ() : Vector3::UnitY();
    joints.push_back(j);
  }
  std::vector<JointSpec> far = joints;
  far[2].xyz = Vector3(1e6, 0, 0);
  const std::string far_msg = ErrorOf([&] { ParseUrdf(UrdfText(links, {}, far), "far.urdf"); });
  EXPECT_NE(far_msg.find("joint 'j3' <origin xyz>"), std::string::npos) << far_msg;
  EXPECT_NE(far_msg.find("within +-10 m"), std::string::npos) << far_msg;
  std::vector<JointSpec> turns = joints;
  turns[4].upper = 628.0;
  const std::string turn_msg =
      ErrorOf([&] { ParseUrdf(UrdfText(links, {}, turns), "turns.urdf"); });
  EXPECT_NE(turn_msg.find("joint 'j5' <limit>"), std::string::npos) << turn_msg;
  EXPECT_NE(turn_msg.find("two turns"), std::string::npos) << turn_msg;
  // A seven-joint arm stays plausible (chains of 1..12 joints).
  EXPECT_EQ(ParseUrdf(SimpleChain(std::vector<std::string>(7, "revolute")), "seven.urdf")
                .num_joints(),
            7);
}

TEST(UrdfModelErrors, UrdfdomsReasonIsInTheMessage) {
  // A revolute joint without <limit>: urdfdom refuses the file and says why (through
  // console_bridge); that reason must be in our message, not only on stderr.
  std::string text = SimpleChain(std::vector<std::string>(6, "revolute"));
  const std::size_t at = text.find("<limit");
  ASSERT_NE(at, std::string::npos);
  text.erase(at, text.find("/>", at) + 2 - at);
  const std::string msg = ErrorOf([&] { ParseUrdf(text, "nolimit.urdf"); });
  EXPECT_NE(msg.find("urdfdom: "), std::string::npos) << msg;
  EXPECT_NE(msg.find("does not specify limits"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nolimit.urdf:"), std::string::npos) << msg;  // the joint's line
}

}  // namespace
}  // namespace twin
