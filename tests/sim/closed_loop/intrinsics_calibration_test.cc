// Zhang's intrinsic calibration on the MuJoCo twin: the twin renders with known intrinsics
// (fx != fy, off-centre principal point, optionally lens distortion), the estimator sees only
// images and the printed board; the estimate is compared with the spec's truth.
#include "calib/vision/intrinsics_calibration.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/procedures/optical_axis_procedure.h"
#include "sim/world/mujoco_handles.h"
#include "sim/cell/twin_cell.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoPose;
using testing::DemoTwinSpec;

// MuJoCo warnings throw (DESIGN.md convention 10), so any warning fails the test.
class IntrinsicsCalibrationTest : public ::testing::Test {
 protected:
  void SetUp() override { InstallMujocoErrorHandlers(); }
};

// The demo cell with non-trivial true intrinsics: fx != fy and an off-centre principal point.
TwinSpec SpecWithIntrinsics(double k1, double k2) {
  TwinSpec spec = DemoTwinSpec();
  spec.camera.intrinsics.fx = 850.0;
  spec.camera.intrinsics.fy = 820.0;
  spec.camera.intrinsics.cx = 530.3;
  spec.camera.intrinsics.cy = 390.7;
  spec.camera.distortion.k1 = k1;
  spec.camera.distortion.k2 = k2;
  return spec;
}

BoardGeometry PrintedBoard(const TwinSpec& spec) {
  return BoardGeometry{spec.board.squares_x, spec.board.squares_y, spec.board.square_m};
}

// Relative errors of the estimate against the spec's truth, printed for the report.
struct Errors {
  double fx, fy, cx_px, cy_px;
};
Errors Compare(const IntrinsicsResult& r, const Intrinsics& truth, const char* label) {
  const PinholeIntrinsics& k = r.intrinsics;
  const Errors e{std::abs(k.fx - truth.fx) / truth.fx, std::abs(k.fy - truth.fy) / truth.fy,
                 std::abs(k.cx - truth.cx), std::abs(k.cy - truth.cy)};
  std::printf("%s: %d views, rms %.3f px; fx %.2f (err %.3f%%), fy %.2f (err %.3f%%), "
              "cx %.2f (err %.2f px), cy %.2f (err %.2f px); k1 %.4f k2 %.4f p1 %.5f p2 %.5f "
              "k3 %.4f; skipped %zu\n",
              label, r.views_used, r.rms_px, k.fx, 100 * e.fx, k.fy, 100 * e.fy, k.cx, e.cx_px,
              k.cy, e.cy_px, r.distortion.k1, r.distortion.k2, r.distortion.p1,
              r.distortion.p2, r.distortion.k3, r.skipped.size());
  for (const std::string& s : r.skipped) std::printf("  skipped %s\n", s.c_str());
  return e;
}

// About 25 views, as a bench calibration would take. Tolerances: a 4x4 board has only 9 inner
// corners per view and, 8 cm wide at about 0.4 m, covers some 170 px of the 1024x768 image, so
// the focal length is weakly constrained (it trades off against the view depths and, with
// distortion free, against k2); measured |df|/f was 0.1-0.7 % over seeds 11-13 (corners are
// accurate to about 0.05 px), so 1 % is stated. The principal point is worse constrained still
// (measured 0.1-4.4 px); 10 px is stated. k2 is not checked: the board never reaches the image
// edge, so k2 came out anywhere from -0.7 to 0.4 for a true 0.05.
constexpr int kViews = 25;

TEST_F(IntrinsicsCalibrationTest, RecoversPinholeIntrinsics) {
  const TwinSpec spec = SpecWithIntrinsics(0.0, 0.0);
  TwinCell cell(spec, "intrinsics_calibration_test");
  const std::vector<JointVector> poses =
      IntrinsicsViewPoses(spec.robots[1].model, DemoPose(), kViews, 11);
  IntrinsicsOptions options;
  options.fix_all_distortion = true;  // the twin renders an ideal pinhole here
  const IntrinsicsResult r =
      CalibrateIntrinsics(cell, 1, poses, PrintedBoard(spec), options);
  ASSERT_EQ(r.status, IntrinsicsStatus::kSuccess) << r.reason;
  const Errors e = Compare(r, spec.camera.intrinsics, "pinhole");
  EXPECT_GE(r.views_used, options.min_views);
  EXPECT_LT(r.rms_px, 0.3);  // corner accuracy is about 0.05 px (DESIGN.md); 0.3 flags a mislock
  EXPECT_LT(e.fx, 0.01);
  EXPECT_LT(e.fy, 0.01);
  EXPECT_LT(e.cx_px, 10.0);
  EXPECT_LT(e.cy_px, 10.0);
}

TEST_F(IntrinsicsCalibrationTest, RecoversIntrinsicsWithRadialDistortion) {
  const TwinSpec spec = SpecWithIntrinsics(-0.12, 0.05);
  TwinCell cell(spec, "intrinsics_calibration_test");
  const std::vector<JointVector> poses =
      IntrinsicsViewPoses(spec.robots[1].model, DemoPose(), kViews, 11);
  const IntrinsicsResult r = CalibrateIntrinsics(cell, 1, poses, PrintedBoard(spec), {});
  ASSERT_EQ(r.status, IntrinsicsStatus::kSuccess) << r.reason;
  const Errors e = Compare(r, spec.camera.intrinsics, "distorted");
  EXPECT_EQ(r.distortion.k3, 0.0);  // fixed by default
  // k1 (true -0.12) came out -0.10 to -0.15 over seeds 11-13; its sign and size are checked.
  EXPECT_GT(r.distortion.k1, -0.2);
  EXPECT_LT(r.distortion.k1, -0.05);
  EXPECT_LT(r.rms_px, 0.3);
  EXPECT_LT(e.fx, 0.01);
  EXPECT_LT(e.fy, 0.01);
  EXPECT_LT(e.cx_px, 10.0);
  EXPECT_LT(e.cy_px, 10.0);
}

// The dedicated target (Cell::MountTarget): a 14 x 10 chessboard of 20 mm squares swapped
// onto the board's bracket, 40 views planned for its size (IntrinsicsViewSpecFor). Over the
// paper scenario's 21 study trials (README.md of e5af83d) fx came within 1e-4 of the truth every
// time; 3e-4 is stated here for another cell (fx != fy, off-centre) and seed, still 3 to 30 times
// below what the 4 x 4 board gives (1e-3..1e-2 with 25 views, RecoversPinholeIntrinsics).
TEST_F(IntrinsicsCalibrationTest, AnIntrinsicsTargetPinsTheFocalLength) {
  TwinSpec spec = SpecWithIntrinsics(0.0, 0.0);
  spec.intrinsics_target = testing::IntrinsicsTarget(spec.board);
  TwinCell cell(spec, "intrinsics_calibration_test");
  ASSERT_EQ(cell.MountTarget(BracketTarget::kIntrinsicsTarget).status, MoveStatus::kSettled);
  const BoardGeometry plate{14, 10, 0.02};
  // The camera in the board robot's base at the demo pose, from the spec's models (a test
  // shortcut for the rough knowledge the procedure uses; the views need only be well spread).
  const Transform X_B1B0 = spec.robots[1].X_WB.inverse() * spec.robots[0].X_WB;
  const Transform X_B1C =
      X_B1B0 * ForwardKinematics(spec.robots[0].model, DemoPose()).flange() * spec.camera.X_FC;
  const std::vector<JointVector> poses =
      PlannedIntrinsicsViews(BoardRobotModel(spec.robots[1].model, spec.board.X_FT), DemoPose(),
                             X_B1C, 40, 5, IntrinsicsViewSpecFor(plate));
  const IntrinsicsResult r = CalibrateIntrinsics(cell, 1, poses, plate, {});
  ASSERT_EQ(r.status, IntrinsicsStatus::kSuccess) << r.reason;
  const Errors e = Compare(r, spec.camera.intrinsics, "14x10 target");
  EXPECT_GE(r.views_used, 20);
  EXPECT_LT(r.rms_px, 0.3);
  EXPECT_LT(e.fx, 3e-4);
  EXPECT_LT(e.fy, 3e-4);
  EXPECT_LT(e.cx_px, 1.0);  // 0.2 px or better in the study; 1 px is 50x the board's bound / 10
  EXPECT_LT(e.cy_px, 1.0);
}

TEST_F(IntrinsicsCalibrationTest, FewerViewsThanMinViewsIsReported) {
  const TwinSpec spec = SpecWithIntrinsics(0.0, 0.0);
  TwinCell cell(spec, "intrinsics_calibration_test");
  const std::vector<JointVector> poses =
      IntrinsicsViewPoses(spec.robots[1].model, DemoPose(), 4, 3);
  const IntrinsicsResult r = CalibrateIntrinsics(cell, 1, poses, PrintedBoard(spec), {});
  EXPECT_EQ(r.status, IntrinsicsStatus::kTooFewViews);
  EXPECT_NE(r.reason.find("min_views = 10"), std::string::npos) << r.reason;
  EXPECT_EQ(r.views_used, 4) << r.reason;
}

// No user sets these options (the scenario sets only fix_all_distortion): a bad one is our bug.
TEST(IntrinsicsOptionsTest, ValidationNamesTheField) {
  IntrinsicsOptions options;
  options.min_views = 2;
  try {
    ValidateIntrinsicsOptions(options);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("min_views"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(ValidateIntrinsicsOptions(IntrinsicsOptions{}));
}

TEST(IntrinsicsViewPosesTest, PosesAreReproducibleAndWithinTheWristRange) {
  const KinematicModel model = testing::ReinovoArm(1);
  const std::vector<JointVector> a = IntrinsicsViewPoses(model, DemoPose(), 25, 5);
  const std::vector<JointVector> b = IntrinsicsViewPoses(model, DemoPose(), 25, 5);
  ASSERT_EQ(a.size(), 25u);
  EXPECT_TRUE(a[0].isApprox(DemoPose()));
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(a[i].isApprox(b[i]));
    EXPECT_TRUE(WithinLimits(model, a[i]));
    const JointVector d = a[i] - DemoPose();
    EXPECT_LE(d.head<3>().cwiseAbs().maxCoeff(), DegToRad(5.0) + 1e-12);
    EXPECT_LE(d.tail<3>().cwiseAbs().maxCoeff(), DegToRad(20.0) + 1e-12);
  }
  EXPECT_THROW(IntrinsicsViewPoses(model, DemoPose(), 0, 5), PreconditionError);
}

}  // namespace
}  // namespace twin
