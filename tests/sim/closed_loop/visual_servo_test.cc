// Closed-loop visual servo on the MuJoCo twin: the estimator side uses only nominal models,
// rough rotations and the true intrinsics; the twin's true geometry is perturbed.
#include "calib/vision/visual_servo.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "sim/world/mujoco_handles.h"
#include "sim/cell/twin_cell.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoPose;
using testing::DemoTwinSpec;

// MuJoCo warnings throw (DESIGN.md convention 10), so any warning fails the test.
class VisualServoTest : public ::testing::Test {
 protected:
  void SetUp() override { InstallMujocoErrorHandlers(); }
};

// The demo cell with geometry errors on both arms (0.5 mm, 0.1 deg per parameter).
TwinSpec PerturbedSpec() {
  TwinSpec spec = DemoTwinSpec();
  EffectSpec e;
  e.type = "geometry_errors";
  e.params = {{"sigma_length_mm", 0.5}, {"sigma_angle_deg", 0.1}};
  e.where = "visual_servo_test";
  spec.effects.push_back(e);
  spec.seed = 7;
  return spec;
}

Matrix3 Rot(const Vector3& axis, double angle_deg) {
  return Eigen::AngleAxisd(DegToRad(angle_deg), axis.normalized()).toRotationMatrix();
}

// Estimator-side knowledge: nominal models (the spec's models before the geometry errors),
// true intrinsics, and base-to-base and hand-eye rotations that are off by about 1 deg.
ServoSetup SetupFor(const TwinSpec& spec, Cell& cell) {
  ServoSetup s;
  s.active_model = spec.robots[0].model;
  s.passive_model = spec.robots[1].model;
  s.passive_robot = 1;
  s.R_BaBp = (spec.robots[0].X_WB.inverse() * spec.robots[1].X_WB).linear() *
             Rot(Vector3(0.3, -1.0, 0.5), 1.0);
  s.R_FC = spec.camera.X_FC.linear() * Rot(Vector3(1.0, 0.4, -0.2), 1.0);
  const Intrinsics& k = spec.camera.intrinsics;
  s.intrinsics = PinholeIntrinsics{k.fx, k.fy, k.cx, k.cy};
  s.board = BoardGeometry{spec.board.squares_x, spec.board.squares_y, spec.board.square_m};
  s.q_active = cell.ReadEncoders(0);
  return s;
}

// A start a few degrees off the demo pose, putting P 10-30 px off the principal point.
JointVector OffsetStart() {
  return DemoPose() + (JointVector(6) << 0.03, 0.02, 0.0, 0.0, 0.0, 0.05).finished();
}

TEST_F(VisualServoTest, AlignsTheFeaturePointWithinTenIterations) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell cell(spec, "visual_servo_test");
  const ServoSetup setup = SetupFor(spec, cell);
  ServoOptions options;  // paper defaults: 0.1 px, 10 iterations, gain 1
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, OffsetStart(), options);
  ASSERT_FALSE(r.image_before.empty());
  const FeatureDetection first = DetectFeaturePoint(r.image_before, setup.board);
  ASSERT_EQ(first.status, DetectionStatus::kFound);
  const double du0 = first.feature_px.x - setup.intrinsics.cx;
  const double dv0 = first.feature_px.y - setup.intrinsics.cy;
  std::printf("servo: start error (%.2f, %.2f) px, status %s, frames %d, moves %d, final "
              "error (%.4f, %.4f) px\n",
              du0, dv0, ToString(r.status), r.frames, r.moves, r.pixel_error.x,
              r.pixel_error.y);
  // The start must be a real test: 10-30 px off the principal point.
  EXPECT_GE(std::hypot(du0, dv0), 10.0);
  EXPECT_LE(std::hypot(du0, dv0), 30.0);
  ASSERT_EQ(r.status, ServoStatus::kAligned) << r.reason;
  EXPECT_TRUE(r.reason.empty());
  EXPECT_LT(std::abs(r.pixel_error.x), 0.1);  // the paper's alignment criterion
  EXPECT_LT(std::abs(r.pixel_error.y), 0.1);
  EXPECT_LE(r.moves, 10);
  EXPECT_EQ(r.frames, r.moves + 1);
  EXPECT_FALSE(r.image_after.empty());
  EXPECT_TRUE(r.q_passive.isApprox(cell.ReadEncoders(1)));
  // Cross-check against the twin's truth (tests only): P is on the optical axis, so its
  // lateral offset in C is about 0.1 px * z / f, a few hundredths of a millimetre.
  const TwinTruth truth = cell.Truth();
  const Vector3 p_CP = truth.X_WC.inverse() * truth.X_WT.translation();
  EXPECT_LT(std::hypot(p_CP.x(), p_CP.y()), 1e-4) << p_CP.transpose();
}

// Forwards to the twin and keeps robot 1's commanded targets and, per joint, the sign of its
// last commanded motion (target against the previous target, as a controller knows it; from
// the second move on).
class MotionLog : public Cell {
 public:
  explicit MotionLog(TwinCell& cell) : cell_(cell) {}
  MoveResult MoveTo(int robot, const JointVector& q) override {
    if (robot == 1) {
      targets.push_back(q);
      if (last_sign.size() != q.size()) last_sign = JointVector::Zero(q.size());
      for (int i = 0; i < q.size() && last_.size() == q.size(); ++i) {
        if (q(i) != last_(i)) last_sign(i) = q(i) > last_(i) ? 1.0 : -1.0;
      }
      last_ = q;
    }
    return cell_.MoveTo(robot, q);
  }
  JointVector ReadEncoders(int robot) override { return cell_.ReadEncoders(robot); }
  cv::Mat GrabImage() override { return cell_.GrabImage(); }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override { return cell_.GrabImageRegion(roi); }
  MoveResult ExchangeTools() override { return cell_.ExchangeTools(); }
  int CameraRobot() override { return cell_.CameraRobot(); }
  JointVector last_sign;
  std::vector<JointVector> targets;

 private:
  TwinCell& cell_;
  JointVector last_;
};

// The servo reports each joint's approach direction (what a backlash acts with): the sign of
// its last motion over the start move and the corrections.
TEST_F(VisualServoTest, ReportsTheDirectionOfEachJointsLastMotion) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell twin(spec, "visual_servo_test");
  MotionLog cell(twin);
  const ServoSetup setup = SetupFor(spec, twin);
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, OffsetStart(), ServoOptions{});
  ASSERT_EQ(r.status, ServoStatus::kAligned) << r.reason;
  ASSERT_GE(r.moves, 1);
  ASSERT_EQ(r.approach.size(), 6);
  // The start move is the log's first: its signs come from the corrections, which move all six
  // joints by IK.
  for (int i = 0; i < 6; ++i) {
    EXPECT_NE(cell.last_sign(i), 0.0) << "joint " << i + 1;
    EXPECT_EQ(r.approach(i), cell.last_sign(i)) << "joint " << i + 1;
  }
}

// After the first whole frame the servo grabs only the predicted board region
// (board_region.h); a first region that misses the board costs one whole frame more.
TEST_F(VisualServoTest, GrabsRegionsAfterTheFirstFrameAndFallsBackWhenTheBoardIsMissing) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell cell(spec, "visual_servo_test");
  const ServoSetup setup = SetupFor(spec, cell);
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, OffsetStart(), ServoOptions{});
  std::printf("servo with regions: frames %d (%d regions, %d fallbacks), moves %d, region "
              "%dx%d px\n",
              r.frames, r.region_frames, r.full_frame_fallbacks, r.moves, r.image_after.cols,
              r.image_after.rows);
  ASSERT_EQ(r.status, ServoStatus::kAligned) << r.reason;
  EXPECT_EQ(r.region_frames, r.frames - 1);  // every frame after the first
  EXPECT_EQ(r.full_frame_fallbacks, 0);
  EXPECT_LT(r.image_after.total(), cell.GrabImage().total() / 4);  // a region, not a frame
  // The last detection is in frame coordinates: on the principal point within tolerance.
  EXPECT_LT(std::abs(r.detection_after.feature_px.x - setup.intrinsics.cx), 0.1);
  EXPECT_LT(std::abs(r.detection_after.feature_px.y - setup.intrinsics.cy), 0.1);

  TwinCell cell2(spec, "visual_servo_test");
  const ServoResult m = AlignFeatureToOpticalAxis(cell2, SetupFor(spec, cell2), OffsetStart(),
                                                  ServoOptions{}, cv::Rect(0, 0, 120, 90));
  ASSERT_EQ(m.status, ServoStatus::kAligned) << m.reason;
  EXPECT_EQ(m.full_frame_fallbacks, 1);
  EXPECT_EQ(m.frames, m.moves + 2);  // the missed region and the whole frame after it

  ServoOptions whole;
  whole.use_regions = false;
  TwinCell cell3(spec, "visual_servo_test");
  const ServoResult w = AlignFeatureToOpticalAxis(cell3, SetupFor(spec, cell3), OffsetStart(),
                                                  whole, cv::Rect(0, 0, 120, 90));
  ASSERT_EQ(w.status, ServoStatus::kAligned) << w.reason;
  EXPECT_EQ(w.region_frames, 0);
  EXPECT_EQ(w.frames, w.moves + 1);
}

// Forwards to the twin and adds to every encoder reading of robot 1 a jitter of +j, -j, +j,
// ... on every joint, one sign per reading: the mean of an even number of readings is the
// twin's reading, a single reading is off by j.
class JitteredEncoders : public Cell {
 public:
  explicit JitteredEncoders(TwinCell& cell) : cell_(cell) {}
  MoveResult MoveTo(int robot, const JointVector& q) override { return cell_.MoveTo(robot, q); }
  JointVector ReadEncoders(int robot) override {
    JointVector q = cell_.ReadEncoders(robot);
    if (robot == 1) {
      q.array() += (reads % 2 == 0 ? kJitter : -kJitter);
      ++reads;
    }
    return q;
  }
  cv::Mat GrabImage() override { return cell_.GrabImage(); }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override { return cell_.GrabImageRegion(roi); }
  MoveResult ExchangeTools() override { return cell_.ExchangeTools(); }
  int CameraRobot() override { return cell_.CameraRobot(); }
  static constexpr double kJitter = 1e-6;  // [rad]: 0.001 px at the board; the servo converges
  int reads = 0;

 private:
  TwinCell& cell_;
};

// encoder_readings: the aligned pose's joints are the mean of that many readings (the demo
// twin has no encoder noise, so the twin's own reading is the reference). Tolerance 1e-12 rad:
// the rounding of a mean of 16 sums.
TEST_F(VisualServoTest, TheAlignedPosesJointsAreTheMeanOfTheEncoderReadings) {
  const TwinSpec spec = PerturbedSpec();
  for (const int readings : {1, 16}) {
    TwinCell twin(spec, "visual_servo_test");
    JitteredEncoders cell(twin);
    const ServoSetup setup = SetupFor(spec, twin);
    ServoOptions options;
    options.encoder_readings = readings;
    const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, OffsetStart(), options);
    ASSERT_EQ(r.status, ServoStatus::kAligned) << r.reason;
    const JointVector error = r.q_passive - twin.ReadEncoders(1);
    if (readings == 1) {
      // One reading carries its jitter in full.
      EXPECT_NEAR(error.cwiseAbs().minCoeff(), JitteredEncoders::kJitter, 1e-12);
    } else {
      EXPECT_LT(error.cwiseAbs().maxCoeff(), 1e-12) << error.transpose();
    }
    EXPECT_GE(cell.reads, readings);
  }
  ServoOptions bad;  // the scenario's encoder_readings is bounded where it is read: our bug
  bad.encoder_readings = 0;
  EXPECT_THROW(ValidateServoOptions(bad), PreconditionError);
}

TEST_F(VisualServoTest, OneIterationIsNotEnough) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell cell(spec, "visual_servo_test");
  const ServoSetup setup = SetupFor(spec, cell);
  ServoOptions options;
  options.max_iterations = 1;
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, OffsetStart(), options);
  std::printf("servo, 1 iteration: status %s, frames %d, error (%.4f, %.4f) px: %s\n",
              ToString(r.status), r.frames, r.pixel_error.x, r.pixel_error.y,
              r.reason.c_str());
  EXPECT_EQ(r.status, ServoStatus::kNotConverged);
  EXPECT_NE(r.reason.find("max_iterations = 1"), std::string::npos) << r.reason;
  EXPECT_EQ(r.moves, 1);
  EXPECT_EQ(r.frames, 2);
  // The sign of eq. 42: one full-gain move must shrink the ~13 px start error to a small
  // fraction (rough rotations of 1 deg and nominal IK leave under a pixel); moving the
  // wrong way would double it.
  const FeatureDetection first = DetectFeaturePoint(r.image_before, setup.board);
  ASSERT_EQ(first.status, DetectionStatus::kFound);
  const double start = std::hypot(first.feature_px.x - setup.intrinsics.cx,
                                  first.feature_px.y - setup.intrinsics.cy);
  EXPECT_LT(std::hypot(r.pixel_error.x, r.pixel_error.y), 0.2 * start);
}

TEST_F(VisualServoTest, BoardOutOfViewIsReported) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell cell(spec, "visual_servo_test");
  const ServoSetup setup = SetupFor(spec, cell);
  // Turning the passive robot's base joint swings the board sideways out of the image.
  JointVector away = DemoPose();
  away(0) += 1.0;
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, away, ServoOptions{});
  std::printf("servo, board away: status %s: %s\n", ToString(r.status), r.reason.c_str());
  EXPECT_EQ(r.status, ServoStatus::kBoardNotFound);
  EXPECT_NE(r.reason.find("inner-corner grid"), std::string::npos) << r.reason;
  EXPECT_EQ(r.frames, 1);
  EXPECT_EQ(r.moves, 0);
}

TEST_F(VisualServoTest, ACorrectionAboveMaxStepIsTakenInSteps) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell twin(spec, "visual_servo_test");
  MotionLog cell(twin);
  const ServoSetup setup = SetupFor(spec, cell);
  // Half a radian on the base joint leaves the board at the image edge, about 0.18 m off axis:
  // at least three moves of 0.05 m before the last, shorter ones.
  JointVector far = DemoPose();
  far(0) += 0.5;
  ServoOptions options;
  options.max_step_m = 0.05;
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, far, options);
  std::printf("servo, far start: status %s, moves %d (%d cut to max_step_m), frames %d: %s\n",
              ToString(r.status), r.moves, r.limited_moves, r.frames, r.reason.c_str());
  EXPECT_EQ(r.status, ServoStatus::kAligned) << r.reason;
  EXPECT_GE(r.limited_moves, 3);
  ASSERT_EQ(static_cast<int>(cell.targets.size()), r.moves + 1);  // the start, then the moves
  double longest = 0;
  for (std::size_t i = 1; i < cell.targets.size(); ++i) {
    const Vector3 a = ForwardKinematics(setup.passive_model, cell.targets[i - 1]).flange().translation();
    const Vector3 b = ForwardKinematics(setup.passive_model, cell.targets[i]).flange().translation();
    longest = std::max(longest, (b - a).norm());
  }
  std::printf("longest commanded flange move %.4f m\n", longest);
  // Each target is the nominal end pose moved by at most max_step_m, solved by nominal IK
  // (its position tolerance is far below a millimetre); the flange carries the board rigidly
  // at the nominal orientation, so it moves by the same amount.
  EXPECT_LE(longest, options.max_step_m + 1e-4);
}

TEST_F(VisualServoTest, StartOutsideTheLimitsIsRefused) {
  const TwinSpec spec = PerturbedSpec();
  TwinCell cell(spec, "visual_servo_test");
  const ServoSetup setup = SetupFor(spec, cell);
  JointVector bad = DemoPose();
  bad(2) = setup.passive_model.links[2].limits.upper + 0.1;
  const ServoResult r = AlignFeatureToOpticalAxis(cell, setup, bad, ServoOptions{});
  EXPECT_EQ(r.status, ServoStatus::kJointLimits);
  EXPECT_NE(r.reason.find("outside its limits"), std::string::npos) << r.reason;
  EXPECT_EQ(r.frames, 0);
}

// The gain stays the user's (calibration.servo.gain admits 2, no stable gain): InputError.
// The other fields are bounded where the scenario is read or set by no user: our bug.
TEST_F(VisualServoTest, BadOptionsThrowNamingTheField) {
  ServoOptions o;
  o.gain = 0.0;
  try {
    ValidateServoOptions(o);
    FAIL() << "gain 0 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gain = 0"), std::string::npos) << e.what();
  }
  o = ServoOptions{};
  o.tolerance_px = -1;
  EXPECT_THROW(ValidateServoOptions(o), PreconditionError);
  o = ServoOptions{};
  o.max_iterations = -1;
  EXPECT_THROW(ValidateServoOptions(o), PreconditionError);
}

}  // namespace
}  // namespace twin
