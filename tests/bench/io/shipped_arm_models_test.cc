// The other makers' arms shipped in models/ (written from ROS-Industrial's figures, each
// file's header names its source): they load as a user of those packages would load them
// (tip_link tool0 beside the frame-only `base` leaf), and their flange sits where the
// package's joint origins put it (the sums below are of those figures, not of our output).
#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "bench/io/scenario.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/spherical_wrist_ik.h"
#include "calib/model/parameters.h"

namespace twin {
namespace {

const std::string kRoot = TWIN_SOURCE_DIR;

JointVector Deg(std::initializer_list<double> d) {
  JointVector q(static_cast<int>(d.size()));
  int i = 0;
  for (double v : d) q(i++) = DegToRad(v);
  return q;
}

void ExpectFlangeAt(const std::string& file, const JointVector& q, const Vector3& p_mm) {
  std::vector<std::string> warnings;
  const KinematicModel m = LoadRobotModel(kRoot + "/models/" + file, {"", "tool0"}, &warnings);
  ASSERT_EQ(m.num_joints(), 6);
  // 1e-6 m: the URDF's figures are exact to the micrometre, the DH conversion to round-off.
  EXPECT_LT((1e3 * EndPose(m, q).translation() - p_mm).norm(), 1e-3) << file;
  // No <inertial> in the package: the stand-in is announced.
  bool massless = false;
  for (const std::string& w : warnings) massless |= w.find("no <inertial>") != std::string::npos;
  EXPECT_TRUE(massless) << file;
}

TEST(ShippedArmModels, AbbIrb2400FlangeWhereThePackagePutsIt) {
  // q = 0: upper arm up (0.615 + 0.705), forearm forward at 0.135 above joint 3;
  // flange 0.1 + 0.755 + 0.085 in front of the base axis.
  ExpectFlangeAt("abb_irb2400.urdf", Deg({0, 0, 0, 0, 0, 0}), Vector3(940, 0, 1455));
}

TEST(ShippedArmModels, KukaKr6R900FlangeWhereThePackagePutsIt) {
  // A2 = -90 deg: upper arm up; A3 = +90 deg: forearm forward. Height 0.4 + 0.455 + 0.035,
  // reach 0.025 + 0.42 + 0.08.
  ExpectFlangeAt("kuka_kr6r900sixx.urdf", Deg({0, -90, 90, 0, 0, 0}), Vector3(525, 0, 890));
}

TEST(ShippedArmModels, WithoutTipLinkTheArmIsStillChosenWithAWarning) {
  std::vector<std::string> warnings;
  const KinematicModel m =
      LoadRobotModel(kRoot + "/models/kuka_kr6r900sixx.urdf", {}, &warnings);
  EXPECT_EQ(m.num_joints(), 6);
  bool chose = false;
  for (const std::string& w : warnings) chose |= w.find("chose 'tool0'") != std::string::npos;
  EXPECT_TRUE(chose);
}

// The twin's measuring tips (used by the handclasp procedure, drawn always) default to the
// flange's centre with their capsule behind the point, inside the wrist. On the KUKA, L_N's z
// points into the wrist (the last link's d < 0), so the default frame is turned by 180 deg
// about x; before that the capsule stood 80 mm out of the flange through the mounted board and
// covered its centre corners (the intrinsics target was then found in 2 of 40 views). On the
// ABB (d > 0) it stays the identity, as on every arm before.
TEST(ShippedArmModels, DefaultTipsPointOutOfTheFlangeFace) {
  const Scenario kuka = LoadScenario(kRoot + "/scenarios/kuka_kr6r900.yaml");
  const Scenario abb = LoadScenario(kRoot + "/scenarios/abb_irb2400.yaml");
  for (int i = 0; i < 2; ++i) {
    const KinematicModel& km = kuka.twin.robots[i].model;
    ASSERT_LT(km.flange().dh.d, 0.0);
    // The capsule runs from the point along the tip frame's -z: into the wrist is -sign(d) z.
    const Vector3 capsule_dir = -kuka.twin.tips[i].X_FTip.linear().col(2);
    EXPECT_GT(capsule_dir.dot(Vector3::UnitZ()), 0.999) << "kuka robot " << i;
    EXPECT_LT(kuka.twin.tips[i].X_FTip.translation().norm(), 1e-12);
    ASSERT_GT(abb.twin.robots[i].model.flange().dh.d, 0.0);
    EXPECT_TRUE(abb.twin.tips[i].X_FTip.isApprox(Transform::Identity())) << "abb robot " << i;
  }
}

// The shipped six-axis arms of the twin have a spherical wrist and parallel joints 2 and 3 (the
// closed-form IK of calib/kinematics/spherical_wrist_ik.h applies), as their makers' drawings
// show; the Motoman's wrist has 30 mm between axes 5 and 6 (link B's a) and the UR5e of
// tests/data three offset wrist axes, so neither has it. Round trip at one pose each as a smoke check (the
// solver's own tests cover it at length).
TEST(ShippedArmModels, SixAxisArmsHaveTheClosedFormInverseKinematics) {
  for (const std::string file : {"models/reinovo_r1.yaml", "models/reinovo_r2.yaml",
                                 "models/abb_irb2400.urdf", "models/kuka_kr6r900sixx.urdf"}) {
    const KinematicModel m = LoadRobotModel(kRoot + "/" + file, {"", file.find(".urdf") !=
                                                                         std::string::npos
                                                                     ? "tool0"
                                                                     : ""});
    std::string why;
    const auto ik = SphericalWristIk::For(m, &why);
    ASSERT_TRUE(ik.has_value()) << file << ": " << why;
    const JointVector q = Deg({10, -20, 30, 40, 50, 60});
    const Transform target = EndPose(m, q);
    double nearest = INFINITY;
    for (const JointVector& s : ik->Solve(target)) nearest = std::min(nearest, (s - q).norm());
    EXPECT_LT(nearest, 1e-6) << file;  // 1e-6 rad: see spherical_wrist_ik_test.cc
  }
  for (const std::string file : {"models/motoman_sda10_right.yaml", "tests/data/ur5e.urdf"}) {
    std::string why;
    const KinematicModel m = LoadRobotModel(
        kRoot + "/" + file, {"", file.find(".urdf") != std::string::npos ? "tool0" : ""});
    EXPECT_FALSE(SphericalWristIk::For(m, &why).has_value()) << file;
    EXPECT_NE(why.find("wrist axes do not meet"), std::string::npos) << why;
  }
}

}  // namespace
}  // namespace twin
