#include "calib/vision/board_region.h"

#include <gtest/gtest.h>

namespace twin {
namespace {

// A 3x3 inner-corner grid with 40 px spacing, top-left corner at (300, 200).
FeatureDetection Grid() {
  FeatureDetection d;
  d.status = DetectionStatus::kFound;
  d.pattern_size = cv::Size(3, 3);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) d.corners.emplace_back(300.0f + 40 * c, 200.0f + 40 * r);
  }
  d.feature_px = cv::Point2d(340, 240);
  return d;
}

TEST(BoardRegionTest, BoundsTheShiftedCornersGrownBySquaresAndSlack) {
  // Without a shift: corners span 300..380 x 200..280; grown by 2.5 squares (100 px) + 10.
  const cv::Rect r = PredictBoardRegion(Grid(), {0, 0}, 2.5, 10.0, cv::Size(1024, 768));
  EXPECT_EQ(r, cv::Rect(190, 90, 301, 301));  // 190 .. 490 inclusive: 380 + 110 = 490
  // Shifted by (-50, 30): the box moves, and grows by a fifth of |shift| (about 11.7 px).
  const cv::Rect s = PredictBoardRegion(Grid(), {-50, 30}, 2.5, 10.0, cv::Size(1024, 768));
  EXPECT_LE(s.x, 300 - 50 - 110 - 11);
  EXPECT_LE(s.y, 200 + 30 - 110 - 11);
  EXPECT_GE(s.x + s.width, 380 - 50 + 110 + 11);
  EXPECT_GE(s.y + s.height, 280 + 30 + 110 + 11);
  // Clipped to the image; nothing for a failed detection.
  const cv::Rect c = PredictBoardRegion(Grid(), {-400, -300}, 2.5, 10.0, cv::Size(1024, 768));
  EXPECT_EQ(c.tl(), cv::Point(0, 0));
  EXPECT_TRUE(PredictBoardRegion(FeatureDetection{}, {0, 0}, 2.5, 10.0, {1024, 768}).empty());
}

TEST(BoardRegionTest, RegionDetectionsMoveIntoFrameCoordinates) {
  FeatureDetection d = Grid();
  ToFrameCoordinates(cv::Point(17, -3), &d);
  EXPECT_EQ(d.corners[0], cv::Point2f(317, 197));
  EXPECT_EQ(d.corners[8], cv::Point2f(397, 277));
  EXPECT_EQ(d.feature_px, cv::Point2d(357, 237));
}

}  // namespace
}  // namespace twin
