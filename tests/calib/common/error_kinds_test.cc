// Which checks of calib/ are bad input and which are broken preconditions (calib/common/
// errors.h): a value a user can reach (a scenario key left unbounded where it is read, a
// measurements file) throws InputError naming where to fix it; a value only our own code
// sets (options no user reaches, sizes of our own structures, forward kinematics) throws
// PreconditionError, which the CLI reports as an internal error.
#include "calib/common/errors.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/measurements/optical_axis_model.h"
#include "calib/measurements/optical_axis_set.h"
#include "calib/model/error_term.h"
#include "calib/model/robot_model.h"
#include "calib/procedures/handclasp_procedure.h"
#include "calib/procedures/optical_axis_procedure.h"
#include "calib/procedures/tracker_calibration.h"
#include "calib/vision/intrinsics_calibration.h"
#include "calib/vision/visual_servo.h"
#include "optical_axis_synthetic.h"
#include "test_models.h"
#include "tracker_synthetic.h"

namespace twin {
namespace {

using testing::MakeOpticalAxisScenario;
using testing::ReinovoLikeModel;
using testing::SyntheticTrackerPoints;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// --- Bad input: reachable by a user's scenario or file, named where it can be fixed. ---

// calibration.calibration_axes is read without bounds (bench/io/calibration_config.cc), so a
// value above the plan's axes reaches the procedure's check.
TEST(ErrorKinds, CalibrationAxesBeyondThePlanIsAnInputErrorNamingTheKeys) {
  OpticalAxisOptions o;
  EXPECT_NO_THROW(ValidateOpticalAxisOptions(o));
  o.calibration_axes = o.planner.num_axes + 1;
  try {
    ValidateOpticalAxisOptions(o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "OpticalAxisOptions.calibration_axes");
    EXPECT_TRUE(Contains(e.message(), "calibration.calibration_axes")) << e.what();
  }
}

// calibration.servo.gain is bounded to [0.01, 2] where it is read, and 2 is no stable gain.
TEST(ErrorKinds, ServoGainOfTwoIsAnInputErrorNamingTheKey) {
  ServoOptions o;
  o.gain = 2.0;
  try {
    ValidateServoOptions(o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "ServoOptions.gain");
    EXPECT_TRUE(Contains(e.message(), "calibration.servo.gain")) << e.what();
  }
}

// Too few points for the unknowns is the tracker file's fault: the message names the file.
TEST(ErrorKinds, TooFewTrackerPointsAreAnInputErrorNamingTheFile) {
  const RobotModel nominal = MakeRobotModel(ReinovoLikeModel(1));
  TrackerCalibrationOptions o;
  o.set.source = "cube.csv";
  try {
    CalibrateFromTracker(nominal, SyntheticTrackerPoints(nominal, 12, 3), {}, o);
    FAIL() << "12 points cannot identify 35 parameters and a tracker pose";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "cube.csv");
    EXPECT_TRUE(Contains(e.message(), "points needed")) << e.what();
  }
}

// Samples come from a measurements file: an axis with too few of them is the file's fault.
TEST(ErrorKinds, AnAxisWithTooFewSamplesIsAnInputError) {
  const auto s = MakeOpticalAxisScenario(5);
  const std::vector<AxisSample> two(s.samples.begin(), s.samples.begin() + 2);
  try {
    OpticalAxisSet set(two);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "samples");
    EXPECT_TRUE(Contains(e.message(), "axis 0 has 2 samples")) << e.what();
  }
}

// --- Broken preconditions: only our own code can break them. ---

// The robots are matched by name and once each where the scenario is read; no user sets
// linearized_max_pairs or kept_images.
TEST(ErrorKinds, OpticalAxisOptionsNoUserReachesArePreconditions) {
  OpticalAxisOptions o;
  o.robots = {0, 0};
  EXPECT_THROW(ValidateOpticalAxisOptions(o), PreconditionError);
  o = OpticalAxisOptions{};
  o.robots = {2};
  EXPECT_THROW(ValidateOpticalAxisOptions(o), PreconditionError);
  o = OpticalAxisOptions{};
  o.intrinsics_views = 2;  // the scenario's key is bounded to 3..500
  EXPECT_THROW(ValidateOpticalAxisOptions(o), PreconditionError);
  o = OpticalAxisOptions{};
  o.kept_images = -1;
  try {
    ValidateOpticalAxisOptions(o);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "kept_images = -1")) << e.what();
  }
  o = OpticalAxisOptions{};
  o.servo.encoder_readings = 0;  // the scenario's key is bounded to 1..10000
  EXPECT_THROW(ValidateOpticalAxisOptions(o), PreconditionError);
}

// A joint vector of the wrong length is our bug (readings come with their own model).
TEST(ErrorKinds, ForwardKinematicsOfAWrongLengthJointVectorIsAPrecondition) {
  const KinematicModel m = ReinovoLikeModel();
  EXPECT_NO_THROW(EndPose(m, JointVector::Zero(m.num_joints())));
  try {
    EndPose(m, JointVector::Zero(m.num_joints() - 1));
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "5 joint angles for a 6-joint chain")) << e.what();
  }
  EXPECT_THROW(ForwardKinematics(m, JointVector::Zero(7)), PreconditionError);
}

// The solved model is a fit of the same model: other terms mean a caller mixed models up.
TEST(ErrorKinds, DormantTermsFromAnotherModelAreAPrecondition) {
  const KinematicModel chain = ReinovoLikeModel();
  const RobotModel plain = MakeRobotModel(chain);
  const RobotModel with = WithTerm(plain, MakeErrorTerm({"joint_compliance", 1, {}}, chain, "r1"));
  EXPECT_THROW(WithDormantTermsFrom(with, plain), PreconditionError);
}

// The directions are fitted to (or planned for) the same samples by the caller.
TEST(ErrorKinds, SamplesWithoutADirectionAreAPrecondition) {
  const auto s = MakeOpticalAxisScenario(6);
  const std::vector<Vector3> one = {Vector3::UnitZ()};  // the samples span 5 axes
  EXPECT_THROW(StackMisalignedErrors(s.nominal, s.samples, one), PreconditionError);
}

// The set's options come from the identification's own; no user sets them.
TEST(ErrorKinds, BadOpticalAxisSetOptionsAreAPrecondition) {
  const auto s = MakeOpticalAxisScenario(7);
  OpticalAxisSetOptions o;
  o.sigma_depth = 0.0;
  EXPECT_THROW(OpticalAxisSet(s.samples, o), PreconditionError);
}

// Every view's corners are paired with the board's points by our own detection loop; with
// that checked, what cv::calibrateCamera refuses is the views' (a status, not an exception).
TEST(ErrorKinds, UnpairedCornersAreAPrecondition) {
  std::vector<std::vector<cv::Point3f>> object(3, std::vector<cv::Point3f>(4));
  std::vector<std::vector<cv::Point2f>> image(3, std::vector<cv::Point2f>(4));
  image[1].pop_back();
  try {
    CalibrateFromCorners(object, image, {0, 1, 2}, cv::Size(640, 480), 3, IntrinsicsOptions{});
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "view 1 has 4 object points but 3 image points")) << e.what();
  }
}

// No user sets the teaching options (the run sets the seed and the orientations).
TEST(ErrorKinds, BadTeachOptionsAreAPrecondition) {
  TeachOptions o;
  EXPECT_NO_THROW(o.Validate());
  o.rolls = 0;
  try {
    o.Validate();
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "TeachOptions.rolls")) << e.what();
  }
}

}  // namespace
}  // namespace twin
