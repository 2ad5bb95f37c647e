#include "calib/vision/board_region.h"

#include <algorithm>
#include <cmath>

namespace twin {

cv::Rect PredictBoardRegion(const FeatureDetection& det, const cv::Point2d& shift,
                            double margin_squares, double slack_px, const cv::Size& image) {
  if (det.status != DetectionStatus::kFound || det.corners.empty()) return cv::Rect();
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (const cv::Point2f& p : det.corners) {
    x0 = std::min<double>(x0, p.x);
    y0 = std::min<double>(y0, p.y);
    x1 = std::max<double>(x1, p.x);
    y1 = std::max<double>(y1, p.y);
  }
  double spacing = 0.0;
  const cv::Size n = det.pattern_size;
  for (int r = 0; r < n.height; ++r) {
    for (int c = 0; c < n.width; ++c) {
      const cv::Point2f& p = det.corners[r * n.width + c];
      if (c + 1 < n.width) spacing = std::max(spacing, cv::norm(det.corners[r * n.width + c + 1] - p));
      if (r + 1 < n.height) spacing = std::max(spacing, cv::norm(det.corners[(r + 1) * n.width + c] - p));
    }
  }
  const double grow = margin_squares * spacing + slack_px + 0.2 * std::hypot(shift.x, shift.y);
  const int left = static_cast<int>(std::floor(x0 + shift.x - grow));
  const int top = static_cast<int>(std::floor(y0 + shift.y - grow));
  const int right = static_cast<int>(std::ceil(x1 + shift.x + grow)) + 1;
  const int bottom = static_cast<int>(std::ceil(y1 + shift.y + grow)) + 1;
  return cv::Rect(left, top, right - left, bottom - top) & cv::Rect(cv::Point(0, 0), image);
}

void ToFrameCoordinates(const cv::Point& origin, FeatureDetection* det) {
  const cv::Point2f o(static_cast<float>(origin.x), static_cast<float>(origin.y));
  for (cv::Point2f& p : det->corners) p += o;
  det->feature_px += cv::Point2d(origin.x, origin.y);
}

}  // namespace twin
