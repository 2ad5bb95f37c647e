#include "calib/diagnosis/discovery_data.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_models.h"

namespace twin::discovery {
namespace {

RobotModel Start() { return MakeRobotModel(twin::testing::ReinovoLikeModel(1)); }

TrackerPoint Point(double q1, const Vector3& p_T, double sigma, int row) {
  TrackerPoint p;
  p.context.q = JointVector::Zero(6);
  p.context.q(0) = q1;
  p.p_T = p_T;
  p.sigma = sigma;
  p.row = row;
  return p;
}

TEST(DiscoveryData, TheTrackerNoiseFloorIsTheStatedSigmasAndTheRepeatsSpread) {
  DiscoveryOptions o;
  o.set.default_sigma = 1e-5;
  // Two points state 2e-5, two take the default; rows 1 and 2 repeat one pose 2 mm apart.
  const std::vector<TrackerPoint> points{Point(0.0, Vector3(0.5, 0, 0), 2e-5, 1),
                                         Point(0.0, Vector3(0.502, 0, 0), 2e-5, 2),
                                         Point(0.3, Vector3(0, 0.5, 0), 0.0, 3),
                                         Point(0.6, Vector3(0, 0, 0.5), 0.0, 4)};
  const TrackerData data(Start(), points, o);
  EXPECT_EQ(data.Sigma(0), 2e-5);
  EXPECT_EQ(data.Sigma(2), 1e-5);
  EXPECT_EQ(data.Where(2), "row 3");
  const NoiseFloor nf = TrackerNoise(data, o);
  // RMS of (2, 2, 1, 1) e-5; without joint noise the per-axis sigma is the tracker's.
  EXPECT_DOUBLE_EQ(nf.tracker_sigma_m, std::sqrt(2.5e-10));
  EXPECT_NEAR(nf.sigma_m, std::sqrt(2.5e-10), 1e-20);  // trace / 3 of s^2 I: rounding only
  EXPECT_EQ(nf.source, "the stated sigmas, the set's default where a point has none");
  // One group of two, each 1 mm from its mean: 2 (1 mm)^2 over 3 (2 - 1) dof.
  EXPECT_EQ(nf.repeated_groups, 1);
  EXPECT_NEAR(nf.repeat_sigma_m, std::sqrt(2e-6 / 3), 1e-12);  // 1e-12 m: rounding of p_T
}

TEST(DiscoveryData, AHeldOutTrackerPointIsScoredAgainstItsStatedNoise) {
  DiscoveryOptions o;
  const RobotModel start = Start();
  MeasurementContext c;
  c.q = JointVector::Zero(6);
  const Vector3 p = EndPose(start, c).translation();
  // Measured 30 um off along x with a stated 10 um: chi-square 9 over 3 dof.
  const std::vector<TrackerPoint> points{Point(0.0, p + Vector3(3e-5, 0, 0), 1e-5, 1)};
  const TrackerData data(start, points, o);
  Fit fit;
  fit.result.model = start;
  CrossValidation cv;
  cv.Resize(1);
  data.HeldOut(fit, {0}, &cv);
  // 1e-15 m: the model's own position rounding at 0.5 m.
  EXPECT_NEAR(cv.e[0](0), -3e-5, 1e-15);
  EXPECT_NEAR(cv.dist2[0], 9e-10, 1e-18);
  EXPECT_NEAR(cv.chi2[0], 9.0, 1e-6);
  EXPECT_EQ(cv.dof, 3.0);
  const Components parts = data.ResidualComponents(cv);
  ASSERT_EQ(parts.size(), 4u);
  EXPECT_EQ(parts[3].first, "norm");
  EXPECT_NEAR(parts[3].second[0], 3e-5, 1e-15);
}

TEST(DiscoveryData, AnOpticalSampleUsesItsOwnSigmasWhereItStatesThem) {
  DiscoveryOptions o;
  o.axis_set.sigma_perpendicular = 5e-5;
  o.axis_set.sigma_depth = 1e-3;
  std::vector<AxisSample> samples(4);
  for (int i = 0; i < 4; ++i) {
    samples[i].axis = i < 2 ? 3 : 1;
    samples[i].q = JointVector::Zero(6);
  }
  samples[0].sigma_offset = 2e-5;
  samples[0].sigma_depth = 4e-4;
  const OpticalData data(Start(), samples, o);
  EXPECT_EQ(data.SigmaOffset(0), 2e-5);
  EXPECT_EQ(data.SigmaDepth(0), 4e-4);
  EXPECT_EQ(data.SigmaOffset(1), 5e-5);
  EXPECT_EQ(data.SigmaDepth(1), 1e-3);
  EXPECT_EQ(data.axes(), (std::vector<int>{1, 3}));
  EXPECT_FALSE(data.depth());  // no sample has a depth
  EXPECT_EQ(data.Where(2), "sample 3 (axis 2)");
  const NoiseFloor nf = OpticalNoise(data, o);
  // RMS of the offsets' sigmas (2, 5, 5, 5) e-5; no depths, so none reported.
  EXPECT_NEAR(nf.tracker_sigma_m, std::sqrt((4 + 3 * 25) / 4.0) * 1e-5, 1e-18);
  EXPECT_EQ(nf.depth_sigma_m, -1.0);
  EXPECT_EQ(nf.source, "each sample's own where known, the stated sigmas elsewhere");
}

}  // namespace
}  // namespace twin::discovery
