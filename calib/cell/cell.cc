#include "calib/cell/cell.h"

#include <cmath>
#include <limits>

namespace twin {

const char* ToString(MoveStatus status) {
  switch (status) {
    case MoveStatus::kSettled: return "settled";
    case MoveStatus::kCollision: return "collision";
    case MoveStatus::kNotSettled: return "not_settled";
    case MoveStatus::kOutOfLimits: return "out_of_limits";
    case MoveStatus::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

const char* ToString(TrackerStatus status) {
  switch (status) {
    case TrackerStatus::kOk: return "ok";
    case TrackerStatus::kNoTracker: return "no_tracker";
    case TrackerStatus::kOutOfRange: return "out_of_range";
    case TrackerStatus::kOccluded: return "occluded";
  }
  return "unknown";
}

const char* ToString(BracketTarget target) {
  switch (target) {
    case BracketTarget::kFeatureBoard: return "feature_board";
    case BracketTarget::kIntrinsicsTarget: return "intrinsics_target";
  }
  return "unknown";
}

cv::Mat Cell::GrabImageRegion(const cv::Rect& roi) {
  const cv::Mat frame = GrabImage();
  const cv::Rect r = roi & cv::Rect(0, 0, frame.cols, frame.rows);
  if (r.empty()) return cv::Mat();
  return frame(r).clone();
}

double ReadTemperatureDeltaK(Cell& cell, int robot, double* reference_C) {
  const double temperature = cell.ReadTemperatureC(robot);
  if (!std::isfinite(temperature)) return std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(*reference_C)) *reference_C = temperature;
  return temperature - *reference_C;
}

}  // namespace twin
