// The intrinsics views' design (calib/vision/intrinsics_calibration.h): the spec for a plate
// and the planned poses honouring it, checked with the same nominal model (no cell, no truth).
#include "calib/vision/intrinsics_calibration.h"

#include <cmath>

#include <gtest/gtest.h>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/procedures/optical_axis_procedure.h"
#include "tests/calib/test_models.h"

namespace twin {
namespace {

TEST(IntrinsicsViewSpecFor, TheFeatureBoardKeepsTheDefaultsALargeTargetStandsBack) {
  const IntrinsicsViewSpec defaults;
  for (const BoardGeometry& small : {BoardGeometry{4, 4, 0.02}, BoardGeometry{8, 6, 0.02}}) {
    const IntrinsicsViewSpec s = IntrinsicsViewSpecFor(small);  // 80 and 160 mm
    EXPECT_EQ(s.min_depth_m, defaults.min_depth_m);
    EXPECT_EQ(s.max_depth_m, defaults.max_depth_m);
    EXPECT_EQ(s.half_angle_x, defaults.half_angle_x);
    EXPECT_EQ(s.min_tilt, defaults.min_tilt);
  }
  // 14 x 10 squares of 20 mm: 0.28 m across; the rule of the header, by hand.
  const IntrinsicsViewSpec s = IntrinsicsViewSpecFor(BoardGeometry{14, 10, 0.02});
  EXPECT_NEAR(s.min_depth_m, 1.43 * 0.28, 1e-12);
  EXPECT_NEAR(s.max_depth_m, 2.14 * 0.28, 1e-12);
  EXPECT_NEAR(s.half_angle_x, DegToRad(17.0) * 0.16 / 0.28, 1e-12);
  EXPECT_NEAR(s.half_angle_y, DegToRad(12.0) * 0.16 / 0.28, 1e-12);
  EXPECT_NEAR(s.min_tilt, DegToRad(40.0), 1e-12);
  EXPECT_NEAR(s.max_tilt, DegToRad(60.0), 1e-12);
}

// The planned poses put the target where the spec says, seen from the camera, by the model
// they were planned with: the centre's depth, its direction off the axis, the tilt.
TEST(PlannedIntrinsicsViews, PosesHonourALargeTargetsSpec) {
  const KinematicModel arm = testing::ReinovoLikeModel(1);
  const Transform X_FT = Transform(Eigen::Translation3d(0, 0, 0.04));
  const KinematicModel board_model = BoardRobotModel(arm, X_FT);
  JointVector q0(6);
  q0 << 0.0, 0.6, -0.6, 0.0, kPi / 2, kPi / 2;
  // A camera 0.5 m in front of the board at q0, looking back at it.
  const Transform X_BT0 = ForwardKinematics(board_model, q0).X_BE;
  Transform X_TC = Transform::Identity();
  X_TC.linear() = Eigen::AngleAxisd(kPi, Vector3::UnitX()).toRotationMatrix();
  X_TC.translation() = Vector3(0, 0, 0.5);
  const Transform X_BC = X_BT0 * X_TC;
  const IntrinsicsViewSpec spec = IntrinsicsViewSpecFor(BoardGeometry{14, 10, 0.02});
  const std::vector<JointVector> poses =
      PlannedIntrinsicsViews(board_model, q0, X_BC, 30, 7, spec);
  ASSERT_EQ(poses.size(), 30u);
  for (const JointVector& q : poses) {
    EXPECT_TRUE(WithinLimits(board_model, q));
    const Transform X_CT = X_BC.inverse() * ForwardKinematics(board_model, q).X_BE;
    const Vector3 p = X_CT.translation();
    // IK converges to well below a micrometre and a microradian: 1e-6 of slack.
    EXPECT_GE(p.z(), spec.min_depth_m - 1e-6);
    EXPECT_LE(p.z(), spec.max_depth_m + 1e-6);
    EXPECT_LE(std::abs(std::atan(p.x() / p.z())), spec.half_angle_x + 1e-6);
    EXPECT_LE(std::abs(std::atan(p.y() / p.z())), spec.half_angle_y + 1e-6);
    const double tilt = std::acos(-X_CT.linear().col(2).dot(p.normalized()));
    EXPECT_GE(tilt, spec.min_tilt - 1e-6);
    EXPECT_LE(tilt, spec.max_tilt + 1e-6);
  }
  EXPECT_EQ(poses, PlannedIntrinsicsViews(board_model, q0, X_BC, 30, 7, spec));
}

}  // namespace
}  // namespace twin
