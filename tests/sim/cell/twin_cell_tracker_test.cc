// The twin's laser tracker (TwinCell::MeasureTracker): readings against the true flange frame,
// range, line of sight and the cells without a tracker.
#include <cmath>

#include <gtest/gtest.h>

#include "sim/cell/twin_cell.h"
#include "calib/common/errors.h"
#include "sim/world/mujoco_handles.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoTwinSpec;
using testing::Pose;

TwinSpec TrackerSpecOnRobot1(double sigma) {
  TwinSpec spec = DemoTwinSpec();
  spec.tracker.present = true;
  spec.tracker.robot = 1;
  // Behind robot 1 (which faces robot 0 from x = 1.2 m), at a height, turned about z.
  spec.tracker.X_WT = Pose(Vector3(3.0, 0.3, 1.0), Vector3::UnitZ(), DegToRad(170.0));
  spec.tracker.p_FR = Vector3(0.03, -0.02, 0.15);
  spec.tracker.sigma_m = sigma;
  return spec;
}

// Noise-free: the reading is the reflector's position, from MuJoCo's flange site, in the
// tracker frame; to rounding (1e-12 m: a few double operations on metre values).
TEST(TwinCellTracker, ANoiseFreeReadingIsTheReflectorInTheTrackerFrame) {
  const TwinSpec spec = TrackerSpecOnRobot1(0.0);
  TwinCell cell(spec);
  const TrackerReading r = cell.MeasureTracker(1);
  ASSERT_EQ(r.status, TrackerStatus::kOk) << r.reason;
  const std::vector<Transform> frames = cell.SiteFrames(1);
  const Transform& X_WF = frames[spec.robots[1].model.num_joints()];
  const Vector3 expected = spec.tracker.X_WT.inverse() * (X_WF * spec.tracker.p_FR);
  EXPECT_LT((r.p_T - expected).norm(), 1e-12);
}

// With noise the readings scatter by sigma per axis: 400 readings at one pose, the sample
// standard deviation within 10 % of sigma (its relative scatter is ~1/sqrt(2 n) = 3.5 %).
TEST(TwinCellTracker, NoisyReadingsScatterBySigma) {
  const double sigma = 1e-5;
  TwinCell cell(TrackerSpecOnRobot1(sigma));
  Vector3 sum = Vector3::Zero(), sum_sq = Vector3::Zero();
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    const TrackerReading r = cell.MeasureTracker(1);
    ASSERT_EQ(r.status, TrackerStatus::kOk);
    sum += r.p_T;
    sum_sq += r.p_T.cwiseProduct(r.p_T);
  }
  const Vector3 mean = sum / n;
  for (int a = 0; a < 3; ++a) {
    const double sd = std::sqrt(std::max(0.0, sum_sq(a) / n - mean(a) * mean(a)) * n / (n - 1));
    EXPECT_NEAR(sd, sigma, 0.1 * sigma) << "axis " << a;
  }
}

TEST(TwinCellTracker, OutOfRangeOccludedAndNoTrackerAreReportedWithReasons) {
  {
    TwinSpec spec = TrackerSpecOnRobot1(0.0);
    spec.tracker.max_range_m = 0.5;
    TwinCell cell(spec);
    const TrackerReading r = cell.MeasureTracker(1);
    EXPECT_EQ(r.status, TrackerStatus::kOutOfRange);
    EXPECT_NE(r.reason.find("beyond"), std::string::npos) << r.reason;
  }
  {
    // A tracker standing behind robot 0, looking through robot 0's arm and base at the
    // reflector on robot 1: the beam along the floor at 5 cm height hits robot 0's base.
    TwinSpec spec = TrackerSpecOnRobot1(0.0);
    spec.tracker.X_WT = Pose(Vector3(-1.0, 0.0, 0.05));
    spec.tracker.p_FR = Vector3::Zero();
    TwinCell cell(spec);
    const TrackerReading r = cell.MeasureTracker(1);
    EXPECT_EQ(r.status, TrackerStatus::kOccluded) << r.reason;
    EXPECT_NE(r.reason.find("blocked by"), std::string::npos) << r.reason;
  }
  {
    TwinCell cell(TrackerSpecOnRobot1(0.0));
    const TrackerReading r = cell.MeasureTracker(0);
    EXPECT_EQ(r.status, TrackerStatus::kNoTracker);
    EXPECT_NE(r.reason.find("robot 2"), std::string::npos) << r.reason;
  }
  {
    TwinCell cell(DemoTwinSpec());
    EXPECT_EQ(cell.MeasureTracker(1).status, TrackerStatus::kNoTracker);
  }
}

TEST(TwinCellTracker, ImplausibleTrackerValuesAreRefusedByName) {
  TwinSpec spec = TrackerSpecOnRobot1(0.0);
  spec.tracker.sigma_m = 0.01;
  EXPECT_THROW(TwinCell cell(spec), InputError);
  spec = TrackerSpecOnRobot1(0.0);
  spec.tracker.p_FR = Vector3(2.0, 0, 0);
  try {
    TwinCell cell(spec);
    FAIL() << "a reflector 2 m from the flange";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tracker.reflector"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twin
