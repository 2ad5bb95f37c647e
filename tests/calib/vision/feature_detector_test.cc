#include "calib/vision/feature_detector.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "calib/common/errors.h"

namespace twin {
namespace {

constexpr int kSquarePx = 40;   // side of one square in the generated pattern [px]
constexpr int kMarginPx = 40;   // white border of the generated pattern [px]

// A 4x4 chessboard pattern, 8-bit grey, (0, 0) square black. In OpenCV's pixel-centre
// convention the centre inner corner lies at (c, c), c = margin + 2 square - 0.5.
cv::Mat Pattern(int squares) {
  const int side = 2 * kMarginPx + squares * kSquarePx;
  cv::Mat p(side, side, CV_8UC1, cv::Scalar(255));
  for (int j = 0; j < squares; ++j) {
    for (int i = 0; i < squares; ++i) {
      if ((i + j) % 2 == 0) {
        p(cv::Rect(kMarginPx + i * kSquarePx, kMarginPx + j * kSquarePx, kSquarePx, kSquarePx))
            .setTo(0);
      }
    }
  }
  return p;
}

// The pattern seen through homography H on a 640x480 grey background, as BGR.
cv::Mat Warp(const cv::Mat& pattern, const cv::Matx33d& H) {
  cv::Mat grey;
  cv::warpPerspective(pattern, grey, cv::Mat(H), cv::Size(640, 480), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(128));
  cv::Mat bgr;
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

cv::Point2d Apply(const cv::Matx33d& H, double x, double y) {
  const cv::Vec3d p = H * cv::Vec3d(x, y, 1.0);
  return {p[0] / p[2], p[1] / p[2]};
}

// Homography: rotate the pattern by `angle` about its centre, scale, perspective tilt, and
// place the pattern centre at (u, v).
cv::Matx33d Homography(double angle_rad, double scale, double tilt, double u, double v) {
  const double c = kMarginPx + 2 * kSquarePx - 0.5;
  const cv::Matx33d centre(1, 0, -c, 0, 1, -c, 0, 0, 1);
  const cv::Matx33d rot(std::cos(angle_rad) * scale, -std::sin(angle_rad) * scale, 0,
                        std::sin(angle_rad) * scale, std::cos(angle_rad) * scale, 0, tilt, 0,
                        1);
  const cv::Matx33d place(1, 0, u, 0, 1, v, 0, 0, 1);
  return place * rot * centre;
}

TEST(FeatureDetectorTest, FindsTheCentreCornerUnderHomographies) {
  const BoardGeometry board{4, 4, 0.02};
  const cv::Mat pattern = Pattern(4);
  const double c = kMarginPx + 2 * kSquarePx - 0.5;
  // Angles of 0, 90, 180 and 200 deg make OpenCV start its ordering at different grid
  // corners; the feature point must not depend on that.
  const double angles_deg[] = {0.0, 17.0, 90.0, 180.0, 200.0};
  const double tilts[] = {0.0, 4e-4};
  for (double angle_deg : angles_deg) {
    for (double tilt : tilts) {
      const cv::Matx33d H = Homography(angle_deg * M_PI / 180.0, 0.9, tilt, 330.0, 250.0);
      const FeatureDetection det = DetectFeaturePoint(Warp(pattern, H), board);
      SCOPED_TRACE("angle " + std::to_string(angle_deg) + " deg, tilt " + std::to_string(tilt));
      ASSERT_EQ(det.status, DetectionStatus::kFound) << det.reason;
      EXPECT_EQ(det.corners.size(), 9u);
      EXPECT_TRUE(det.reason.empty());
      const cv::Point2d expected = Apply(H, c, c);
      // Bilinear warping of a sharp pattern blurs each edge by under one pixel symmetrically;
      // cornerSubPix then locates a corner to a few hundredths of a pixel. 0.1 px is the
      // servo's tolerance and leaves margin.
      EXPECT_NEAR(det.feature_px.x, expected.x, 0.1);
      EXPECT_NEAR(det.feature_px.y, expected.y, 0.1);
    }
  }
}

TEST(FeatureDetectorTest, AcceptsAGreyImage) {
  const cv::Matx33d H = Homography(0.3, 1.0, 0.0, 300.0, 220.0);
  cv::Mat grey;
  cv::cvtColor(Warp(Pattern(4), H), grey, cv::COLOR_BGR2GRAY);
  const FeatureDetection det = DetectFeaturePoint(grey, BoardGeometry{4, 4, 0.02});
  ASSERT_EQ(det.status, DetectionStatus::kFound) << det.reason;
  const double c = kMarginPx + 2 * kSquarePx - 0.5;
  EXPECT_NEAR(cv::norm(det.feature_px - Apply(H, c, c)), 0.0, 0.1);  // as above
}

TEST(FeatureDetectorTest, BlankImageIsNotFoundWithAReason) {
  const cv::Mat blank(480, 640, CV_8UC3, cv::Scalar(200, 200, 200));
  const FeatureDetection det = DetectFeaturePoint(blank, BoardGeometry{4, 4, 0.02});
  EXPECT_EQ(det.status, DetectionStatus::kNotFound);
  EXPECT_NE(det.reason.find("3x3"), std::string::npos) << det.reason;
  EXPECT_TRUE(det.corners.empty());
  EXPECT_STREQ(ToString(det.status), "not_found");
}

TEST(FeatureDetectorTest, WrongBoardSizeIsNotFound) {
  // A 4x4 board searched as 6x6: no complete 5x5 grid.
  const cv::Mat image = Warp(Pattern(4), Homography(0.0, 1.0, 0.0, 320.0, 240.0));
  EXPECT_EQ(DetectFeaturePoint(image, BoardGeometry{6, 6, 0.02}).status,
            DetectionStatus::kNotFound);
}

// An nx x ny chessboard of `square` px squares with a white border of one square, seen
// through H on a `size` grey background and lit unevenly: the brightness falls from 1 at
// column x1 to 0.1 at column x0 (and stays there beyond), so that the white squares on one side
// are darker than the black ones on the other and no global threshold separates them. Then
// blurred (sigma 1 px, about a lens' and a sensor's spread), with Gaussian pixel noise of
// sigma 2 grey levels from a fixed seed. BGR.
cv::Mat UnevenlyLitBoard(int nx, int ny, int square, const cv::Matx33d& H, cv::Size size,
                         int x0, int x1) {
  cv::Mat p((ny + 2) * square, (nx + 2) * square, CV_8UC1, cv::Scalar(230));
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      if ((i + j) % 2 == 0) {
        p(cv::Rect((i + 1) * square, (j + 1) * square, square, square)).setTo(30);
      }
    }
  }
  cv::Mat warped, lit(size, CV_32FC1), noise(size, CV_32FC1), grey, bgr;
  cv::warpPerspective(p, warped, cv::Mat(H), size, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                      cv::Scalar(128));
  warped.convertTo(lit, CV_32FC1);
  for (int x = 0; x < size.width; ++x) {
    lit.col(x) *= 0.1 + 0.9 * std::clamp((x - x0) / (x1 - x0 + 0.0), 0.0, 1.0);
  }
  cv::GaussianBlur(lit, lit, cv::Size(0, 0), 1.0);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
  lit += noise;
  lit.convertTo(grey, CV_8UC1);  // rounds and saturates
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

// Largest distance from a corner of `a` to the nearest corner of `b` [px] (the two searches
// may start their ordering at different grid corners).
double LargestCornerGap(const FeatureDetection& a, const FeatureDetection& b) {
  double largest = 0.0;
  for (const cv::Point2f& p : a.corners) {
    double nearest = 1e9;
    for (const cv::Point2f& q : b.corners) nearest = std::min<double>(nearest, cv::norm(p - q));
    largest = std::max(largest, nearest);
  }
  return largest;
}

TEST(FeatureDetectorTest, TheHalfSizeAdaptiveSearchEndsOnTheFullSizeOnesCorners) {
  // The intrinsics target's 14 x 10 squares filling much of a 1024 x 768 frame, tilted.
  const BoardGeometry board{14, 10, 0.02};
  const int square = 48;
  const double c = 8 * square;  // about the pattern's centre [px]
  const cv::Matx33d centre(1, 0, -c, 0, 1, -0.7 * c, 0, 0, 1);
  const double a = 0.2;
  const cv::Matx33d tilt(std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 2e-4, 1e-4, 1);
  const cv::Matx33d place(1, 0, 512, 0, 1, 384, 0, 0, 1);
  const cv::Mat image =
      UnevenlyLitBoard(14, 10, square, place * tilt * centre, cv::Size(1024, 768), 0, 1023);
  DetectorOptions full_size;
  full_size.coarse_search = false;
  const FeatureDetection coarse = DetectFeaturePoint(image, board);
  const FeatureDetection full = DetectFeaturePoint(image, board, full_size);
  ASSERT_EQ(coarse.status, DetectionStatus::kFound) << coarse.reason;
  ASSERT_EQ(full.status, DetectionStatus::kFound) << full.reason;
  EXPECT_TRUE(coarse.found_in_half_size);  // the global threshold found nothing
  EXPECT_FALSE(full.found_in_half_size);
  ASSERT_EQ(coarse.corners.size(), 13u * 9u);
  // Both refine on the full image from starts under a pixel apart; cornerSubPix stops when a
  // step is under 1e-4 px, so the two end on the same saddle points to a few thousandths of a
  // pixel. 0.01 px is a tenth of the servo's tolerance.
  EXPECT_LT(LargestCornerGap(coarse, full), 0.01);
  EXPECT_LT(cv::norm(coarse.feature_px - full.feature_px), 0.01);
}

// The boards are bounded where the scenario is read and the images are the cell's frames: a
// bad one here is a broken precondition naming the field.
TEST(FeatureDetectorTest, BrokenPreconditionsThrowNamingTheField) {
  const cv::Mat image(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
  try {
    DetectFeaturePoint(image, BoardGeometry{5, 4, 0.02});
    FAIL() << "odd squares_x accepted";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("squares_x = 5"), std::string::npos) << e.what();
  }
  try {
    DetectFeaturePoint(image, BoardGeometry{4, 4, -0.01});
    FAIL() << "negative square_m accepted";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("square_m"), std::string::npos) << e.what();
  }
  EXPECT_THROW(DetectFeaturePoint(cv::Mat(), BoardGeometry{}), PreconditionError);
  EXPECT_THROW(DetectFeaturePoint(cv::Mat(10, 10, CV_32FC1), BoardGeometry{}),
               PreconditionError);
}

}  // namespace
}  // namespace twin
