#include "sim/render/camera_image.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace twin {
namespace {

Distortion LensDistortion() {
  Distortion D;
  D.k1 = -0.12;
  D.k2 = 0.05;
  D.p1 = 0.0005;
  D.p2 = -0.0003;
  return D;
}

// Each distorted pixel samples the canvas at an ideal point; cv::projectPoints with D must put
// that point back on the pixel. 0.01 px is far below detection noise (about 0.05 px); the map
// is solved to 1e-10 px and stored as float (about 6e-5 px at 1000 px).
TEST(DistortionMapper, MapsEveryPixelWhereProjectPointsPutsIt) {
  const Intrinsics K;
  const Distortion D = LensDistortion();
  const DistortionMapper mapper(K, D);
  const Intrinsics& C = mapper.canvas();
  ASSERT_EQ(mapper.map_x().size(), cv::Size(K.width, K.height));
  std::vector<cv::Point3d> rays;
  std::vector<cv::Point2d> pixels;
  for (int v = 0; v < K.height; v += 7) {
    for (int u = 0; u < K.width; u += 7) {
      const double cu = mapper.map_x().at<float>(v, u), cv_ = mapper.map_y().at<float>(v, u);
      rays.emplace_back((cu - C.cx) / C.fx, (cv_ - C.cy) / C.fy, 1.0);
      pixels.emplace_back(u, v);
      // The canvas holds every sampled point with room for bilinear neighbours.
      EXPECT_TRUE(cu >= 1 && cv_ >= 1 && cu <= C.width - 2 && cv_ <= C.height - 2);
    }
  }
  const cv::Matx33d Km(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  const cv::Vec<double, 5> Dv(D.k1, D.k2, D.p1, D.p2, D.k3);
  std::vector<cv::Point2d> projected;
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), Km, Dv, projected);
  double worst = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    worst = std::max(worst, cv::norm(projected[i] - pixels[i]));
  }
  std::printf("[ measured ] distortion map vs cv::projectPoints: max %.2e px\n", worst);
  EXPECT_LT(worst, 0.01);
  // Barrel distortion: the canvas is larger, same focal lengths.
  EXPECT_GT(C.width, K.width);
  EXPECT_GT(C.height, K.height);
  EXPECT_EQ(C.fx, K.fx);
  EXPECT_EQ(C.fy, K.fy);
}

TEST(DistortionMapper, ZeroDistortionIsIdentity) {
  const Intrinsics K;
  const DistortionMapper mapper(K, Distortion());
  EXPECT_EQ(mapper.canvas().width, K.width);
  EXPECT_EQ(mapper.canvas().height, K.height);
  EXPECT_EQ(mapper.canvas().cx, K.cx);
  EXPECT_EQ(mapper.canvas().cy, K.cy);
  cv::Mat image(K.height, K.width, CV_8UC3);
  cv::randu(image, 0, 256);
  const cv::Mat out = mapper.Apply(image);
  EXPECT_EQ(cv::norm(out, image, cv::NORM_INF), 0.0);
}

TEST(DistortionMapper, ApplyMovesAFeatureToItsDistortedPixel) {
  const Intrinsics K;
  const DistortionMapper mapper(K, LensDistortion());
  const Intrinsics& C = mapper.canvas();
  // A bright dot at the ideal canvas point of distorted pixel (100, 80) lands there.
  const double cu = mapper.map_x().at<float>(80, 100), cv_ = mapper.map_y().at<float>(80, 100);
  cv::Mat canvas = cv::Mat::zeros(C.height, C.width, CV_8UC1);
  cv::circle(canvas, cv::Point(cvRound(cu), cvRound(cv_)), 3, cv::Scalar(255), cv::FILLED);
  const cv::Mat out = mapper.Apply(canvas);
  ASSERT_EQ(out.size(), cv::Size(K.width, K.height));
  cv::Point peak;
  cv::minMaxLoc(out, nullptr, nullptr, nullptr, &peak);
  EXPECT_LE(std::abs(peak.x - 100), 2);  // the dot is 7 px wide and rounded to whole pixels
  EXPECT_LE(std::abs(peak.y - 80), 2);
  EXPECT_THROW(mapper.Apply(cv::Mat::zeros(K.height, K.width, CV_8UC1)), std::invalid_argument);
}

// Over 1024 x 768 x 3 samples the standard error of a sample std is below 0.1 %; rounding to
// whole grey levels adds 1/12 level^2 of variance (+1 % at sigma 2). 5 % bounds both with a wide
// margin while catching a wrong scale (e.g. variance for std, or one draw shared by channels).
TEST(AddImageNoise, SampleStdMatchesSigma) {
  for (double sigma : {2.0, 8.0}) {
    cv::Mat image(768, 1024, CV_8UC3, cv::Scalar::all(128));
    AddImageNoise(&image, sigma, 7);
    cv::Scalar mean, stddev;
    cv::meanStdDev(image.reshape(1), mean, stddev);
    EXPECT_NEAR(stddev[0], sigma, 0.05 * sigma);
    EXPECT_NEAR(mean[0], 128.0, 0.05);  // zero-mean: 0.01 levels standard error
  }
}

TEST(AddImageNoise, ChannelsAreIndependentAndSeeded) {
  cv::Mat a(768, 1024, CV_8UC3, cv::Scalar::all(128));
  cv::Mat b = a.clone(), c = a.clone();
  AddImageNoise(&a, 5, 42);
  AddImageNoise(&b, 5, 42);
  AddImageNoise(&c, 5, 43);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);
  std::vector<cv::Mat> ch;
  cv::split(a, ch);
  EXPECT_GT(cv::norm(ch[0], ch[1], cv::NORM_L1), 0.0);
}

TEST(AddImageNoise, SaturatesInsteadOfWrapping) {
  cv::Mat black(768, 1024, CV_8UC1, cv::Scalar(0));
  cv::Mat white(768, 1024, CV_8UC1, cv::Scalar(255));
  AddImageNoise(&black, 10, 1);
  AddImageNoise(&white, 10, 2);
  double bmax, wmin;
  cv::minMaxLoc(black, nullptr, &bmax);
  cv::minMaxLoc(white, &wmin, nullptr);
  EXPECT_LT(bmax, 100);  // 10 sigma: a wrapped negative sample would read 200+
  EXPECT_GT(wmin, 155);
  // Clipped half-normal: mean sigma / sqrt(2 pi) = 4.0 levels.
  EXPECT_NEAR(cv::mean(black)[0], 10 / std::sqrt(2 * 3.14159265358979), 0.2);
}

}  // namespace
}  // namespace twin

namespace twin {
namespace {

// A region of the distorted image from only the canvas region it samples equals the whole
// remap there exactly: the same bilinear weights (maps shifted by whole pixels) on the same
// canvas pixels.
TEST(DistortionMapper, RegionFromItsCanvasRegionEqualsTheWholeRemap) {
  Intrinsics K;
  Distortion D;
  D.k1 = -0.12;
  D.k2 = 0.03;
  D.p1 = 0.001;
  D.p2 = -0.0005;
  const DistortionMapper mapper(K, D);
  cv::Mat canvas(mapper.canvas().height, mapper.canvas().width, CV_8UC3);
  cv::randu(canvas, cv::Scalar::all(0), cv::Scalar::all(256));
  const cv::Mat full = mapper.Apply(canvas);
  for (const cv::Rect& roi : {cv::Rect(412, 284, 200, 200), cv::Rect(0, 0, 160, 120),
                              cv::Rect(864, 648, 160, 120), cv::Rect(3, 700, 1021, 68)}) {
    const cv::Rect c = mapper.CanvasRegion(roi);
    EXPECT_TRUE((c & cv::Rect(0, 0, canvas.cols, canvas.rows)) == c);
    const cv::Mat part = mapper.ApplyRegion(canvas(c).clone(), c, roi);
    ASSERT_EQ(part.size(), roi.size());
    EXPECT_EQ(cv::norm(part, full(roi), cv::NORM_INF), 0.0) << roi;
    // Only what is needed: a centred 200 px region samples little more than itself.
    if (roi.width == 200) EXPECT_LT(c.area(), 2 * roi.area());
  }
  EXPECT_THROW(mapper.ApplyRegion(canvas, cv::Rect(0, 0, 10, 10), cv::Rect(0, 0, 5, 5)),
               std::invalid_argument);
  const DistortionMapper none(K, Distortion());
  EXPECT_EQ(none.CanvasRegion(cv::Rect(5, 6, 7, 8)), cv::Rect(5, 6, 7, 8));
}

}  // namespace
}  // namespace twin
