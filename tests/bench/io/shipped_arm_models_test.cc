// The other makers' arms shipped in models/ (written from ROS-Industrial's figures, each
// file's header names its source): they load as a user of those packages would load them
// (tip_link tool0 beside the frame-only `base` leaf), and their flange sits where the
// package's joint origins put it (the sums below are of those figures, not of our output).
#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
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

}  // namespace
}  // namespace twin
