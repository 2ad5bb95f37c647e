// The scale measurement of IdentifyNonlinear (beyond Zhu et al. 2019): depths of the feature
// point along each axis, measured from the board pose, make the uniform scale of the arm
// identifiable. Synthetic data: the recorded joint angles of optical_axis_synthetic.h and the
// exact distance of the true feature point from the camera point on each axis.
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "calib/identification/nonlinear_identification.h"
#include "optical_axis_synthetic.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::MakeOpticalAxisScenario;
using testing::RandomJoints;

// Largest feature-point distance [m] over 50 random configurations after the best rigid
// (scale false) or similarity (scale true) transform mapping a onto b.
double Residual(const KinematicModel& a_model, const KinematicModel& b_model, bool scale) {
  std::mt19937_64 rng(7);
  Eigen::Matrix3Xd a(3, 50), b(3, 50);
  for (int i = 0; i < 50; ++i) {
    const JointVector q = RandomJoints(b_model, rng);
    a.col(i) = EndPose(a_model, q).translation();
    b.col(i) = EndPose(b_model, q).translation();
  }
  const Eigen::Matrix4d T = Eigen::umeyama(a, b, scale);
  return ((T.topLeftCorner<3, 3>() * a).colwise() + T.topRightCorner<3, 1>() - b)
      .colwise()
      .norm()
      .maxCoeff();
}

// Samples with depths: distance of the true point from the axis' camera point [m], plus noise.
std::vector<AxisSample> WithDepths(const testing::OpticalAxisScenario& s, double sigma,
                                   std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<AxisSample> out = s.samples;
  for (AxisSample& smp : out) {
    const Line3& axis = s.axes[smp.axis];
    smp.depth = (EndPose(s.truth, smp.q).translation() - axis.point).dot(axis.direction) +
                (sigma > 0 ? noise(rng) : 0.0);
  }
  return out;
}

TEST(ScaleMeasurement, DepthsMakeTheUniformScaleIdentifiable) {
  const auto s = MakeOpticalAxisScenario(42);
  const NonlinearIdentificationResult without = IdentifyNonlinear(s.nominal, s.samples);
  const NonlinearIdentificationResult with = IdentifyNonlinear(s.nominal, WithDepths(s, 0, 1));
  EXPECT_FALSE(without.depth_used);
  ASSERT_TRUE(with.depth_used);
  // Theory: line data miss rotation about and translation along base z and the uniform scale;
  // depths measure the scale, so exactly one more direction becomes identifiable.
  EXPECT_EQ(with.observability.rank, without.observability.rank + 1);
  EXPECT_EQ(with.observability.unidentifiable.size() + 1, without.observability.unidentifiable.size());
  const double rigid_without = Residual(without.model, s.truth, false);
  const double rigid_with = Residual(with.model, s.truth, false);
  std::printf("[ measured ] noise-free: rigid-gauge residual %.3g m without depths, %.3g m with; "
              "scale %.9f\n",
              rigid_without, rigid_with, with.scale);
  EXPECT_EQ(with.status, NonlinearIdentificationStatus::kConverged);
  // Noise-free: the truth up to the synthetic servo's floor (IK to 1e-7 m, as in
  // nonlinear_identification_test); 1e-6 m leaves margin.
  EXPECT_LT(rigid_with, 1e-6);
  // Without depths the scale error of the random 3 mm length errors stays (mm level).
  EXPECT_GT(rigid_without, 1e-4);
}

TEST(ScaleMeasurement, NoisyDepthsGiveTheScaleToTheirPrecision) {
  const auto s = MakeOpticalAxisScenario(42);
  // 0.1 mm depth noise: what solvePnP gives on a 4 x 4 board at 0.3-0.5 m (the paper scenario's
  // RMS depth residual is 0.09-0.11 mm).
  const NonlinearIdentificationResult r = IdentifyNonlinear(s.nominal, WithDepths(s, 1e-4, 3));
  ASSERT_TRUE(r.depth_used);
  const double rigid = Residual(r.model, s.truth, false);
  std::printf("[ measured ] 0.1 mm depth noise: rigid-gauge residual %.3g m, depth weight %.3g, "
              "RMS depth residual %.3g m\n",
              rigid, r.depth_weight, r.rms_depth_residual);
  // 50 depths over 5 axes spanning 0.18 m each fix the scale to ~1e-4 / (0.18 * sqrt(5 * 10 /
  // 12)) ~ 3e-4 relative, i.e. ~0.3 mm at 1 m from the base; 1 mm bounds a 3-sigma draw.
  EXPECT_LT(rigid, 1e-3);
  // The estimated weight sigma_perpendicular / sigma_depth: perpendicular residuals are the
  // IK floor (1e-7 m) against 1e-4 m depth noise, so far below 1.
  EXPECT_LT(r.depth_weight, 0.05);
  EXPECT_NEAR(r.rms_depth_residual, 1e-4, 5e-5);  // the noise it was given, +-50 %
}

TEST(ScaleMeasurement, EachSamplesOwnDepthSigmaNarrowsTheScale) {
  // A board's depth noise grows with its distance from the camera (solvePnP), so the samples of
  // a real run carry sigmas that differ several-fold. Here each sample's depth sigma is drawn
  // log-uniformly in 0.02-0.2 mm and its depth noise drawn with that sigma. Weighting by the
  // samples' own sigmas (the default) against weighting them alike, over 12 noise draws: the
  // weighted least squares is the minimum-variance one, and for this spread of sigmas its
  // variance is about 1 / 4.6 of the uniform one (mean sigma^2 against 1 / mean sigma^-2).
  const auto s = MakeOpticalAxisScenario(42);
  double sum_own = 0.0, sum_alike = 0.0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    std::mt19937_64 rng(100 + seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::vector<AxisSample> samples = WithDepths(s, 0.0, 1);
    for (AxisSample& smp : samples) {
      smp.sigma_depth = 2e-5 * std::pow(10.0, u(rng));
      smp.depth += smp.sigma_depth * unit(rng);
    }
    NonlinearIdentificationOptions alike;
    alike.use_sample_sigmas = false;
    const NonlinearIdentificationResult own = IdentifyNonlinear(s.nominal, samples);
    const NonlinearIdentificationResult same = IdentifyNonlinear(s.nominal, samples, alike);
    ASSERT_TRUE(own.depth_used && same.depth_used);
    const double e_own = Residual(own.model, s.truth, false);
    const double e_alike = Residual(same.model, s.truth, false);
    sum_own += e_own * e_own;
    sum_alike += e_alike * e_alike;
  }
  const double rms_own = std::sqrt(sum_own / 12), rms_alike = std::sqrt(sum_alike / 12);
  std::printf("[ measured ] rigid-gauge residual RMS over 12 draws: %.3g m with the samples' own "
              "depth sigmas, %.3g m with uniform weights\n",
              rms_own, rms_alike);
  // Expected RMS ratio about 1 / sqrt(4.6) = 0.47; 0.75 leaves room for 12 draws' spread (the
  // ratio of two 12-draw RMS values varies by about +-30 %) and still fails if the sigmas are
  // ignored (ratio 1).
  EXPECT_LT(rms_own, 0.75 * rms_alike);
}

}  // namespace
}  // namespace twin
