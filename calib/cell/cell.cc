#include "calib/cell/cell.h"

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

}  // namespace twin
