// The laser-tracker procedure (calib/procedures/tracker_procedure.h) against a scripted cell:
// what it records of each point, here the temperature of a cell whose robot has a sensor.
#include "calib/procedures/tracker_procedure.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "calib/model/robot_model.h"
#include "test_models.h"

namespace twin {
namespace {

// A cell whose robot 1 goes wherever it is sent (its encoders read the target), whose tracker
// sees the nominal model's reflector exactly, and whose temperature sensor reads a scripted
// sequence, one value per call (NaN: no sensor).
class ScriptedCell : public Cell {
 public:
  ScriptedCell(KinematicModel model, std::vector<double> temperatures)
      : model_(std::move(model)), temperatures_(std::move(temperatures)) {
    q_ = ZeroJoints(model_);
  }
  MoveResult MoveTo(int, const JointVector& q) override {
    q_ = q;
    clock_ += 8.0;
    return {};
  }
  JointVector ReadEncoders(int) override { return q_; }
  cv::Mat GrabImage() override { return {}; }
  MoveResult ExchangeTools() override { return {}; }
  int CameraRobot() override { return 0; }
  double ClockSeconds() override { return clock_; }
  double ReadTemperatureC(int robot) override {
    EXPECT_EQ(robot, 1);
    ++reads_;
    if (temperatures_.empty()) return std::numeric_limits<double>::quiet_NaN();
    return temperatures_[std::min(reads_ - 1, static_cast<int>(temperatures_.size()) - 1)];
  }
  TrackerReading MeasureTracker(int) override {
    TrackerReading r;
    r.status = TrackerStatus::kOk;
    r.p_T = EndPose(model_, q_).translation();
    r.time_s = clock_;
    return r;
  }
  int reads() const { return reads_; }

 private:
  KinematicModel model_;
  std::vector<double> temperatures_;
  JointVector q_;
  double clock_ = 0.0;
  int reads_ = 0;
};

TrackerProcedureOptions Options() {
  TrackerProcedureOptions o;
  o.poses = 40;
  o.seed = 3;
  return o;
}

// Each point carries its sensor reading minus the first point's, and the result the first
// reading as the reference: the procedure reads the sensor once per point, after the tracker.
TEST(TrackerProcedure, EachPointCarriesItsTemperatureChangeSinceTheFirstPoint) {
  const KinematicModel model = WithReflector(testing::ReinovoLikeModel(1), Vector3(0.04, -0.03, 0.08));
  std::vector<double> readings;
  for (int k = 0; k < 40; ++k) readings.push_back(21.0 + 0.25 * k);
  ScriptedCell cell(model, readings);
  const TrackerProcedureResult r = RunTrackerProcedure(cell, 1, model, Options());
  ASSERT_EQ(r.points.size(), 40u);
  EXPECT_EQ(cell.reads(), 40);
  EXPECT_EQ(r.temperature_reference_C, 21.0);
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(r.points[k].context.has_temperature()) << "point " << k;
    // 0.25 K steps of values exact in binary: the differences are exact.
    EXPECT_EQ(r.points[k].context.temperature_delta_K, 0.25 * k) << "point " << k;
  }
}

// A cell without a sensor: no point carries a temperature, and the reference says so (NaN).
TEST(TrackerProcedure, ACellWithoutASensorRecordsNoTemperature) {
  const KinematicModel model = WithReflector(testing::ReinovoLikeModel(1), Vector3(0.04, -0.03, 0.08));
  ScriptedCell cell(model, {});
  const TrackerProcedureResult r = RunTrackerProcedure(cell, 1, model, Options());
  ASSERT_EQ(r.points.size(), 40u);
  EXPECT_TRUE(std::isnan(r.temperature_reference_C));
  for (const TrackerPoint& p : r.points) EXPECT_FALSE(p.context.has_temperature());
}

}  // namespace
}  // namespace twin
