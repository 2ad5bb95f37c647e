#include "calib/diagnosis/statistics.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin::stats {
namespace {

// Closed forms: chi-square with 2 dof has tail exp(-x/2); with 1 dof erfc(sqrt(x/2)); and for a
// whole a, Q(a, x) = exp(-x) sum_(j < a) x^j / j!. Tolerance 1e-12 relative: the series and
// the continued fraction stop at 1e-14.
TEST(Statistics, ChiSquareTailMatchesClosedForms) {
  for (double x : {0.01, 0.5, 1.0, 2.0, 5.0, 10.0, 30.0, 80.0}) {
    EXPECT_NEAR(ChiSquareUpperTail(x, 2.0), std::exp(-0.5 * x), 1e-12 * std::exp(-0.5 * x)) << x;
    const double one = std::erfc(std::sqrt(0.5 * x));
    EXPECT_NEAR(ChiSquareUpperTail(x, 1.0), one, 1e-12 * one + 1e-300) << x;
    double sum = 0, term = 1;
    for (int j = 0; j < 5; ++j) {
      sum += term;
      term *= x / (j + 1);
    }
    const double q5 = std::exp(-x) * sum;
    EXPECT_NEAR(UpperIncompleteGammaRatio(5.0, x), q5, 1e-12 * q5) << x;
  }
  EXPECT_DOUBLE_EQ(ChiSquareUpperTail(0.0, 10.0), 1.0);
  // Its median is close to dof (1 - 2 / (9 dof))^3 for many dof (Wilson-Hilferty): 0.5 to 1e-3.
  const double k = 600.0;
  EXPECT_NEAR(ChiSquareUpperTail(k * std::pow(1.0 - 2.0 / (9.0 * k), 3.0), k), 0.5, 1e-3);
}

// Wald by hand: C = diag(4, 1) and a = (2, 3) give W = 4 / 4 + 9 / 1 = 10 on 2 dof, tail
// exp(-5); rotated by 30 deg (a -> R a, C -> R C R') nothing changes. A singular C (rank 1,
// direction u) counts only a's component along u: W = (u.a)^2 / lambda on 1 dof. A zero C, or
// an empty estimate, is no test (p 1).
TEST(Statistics, WaldTestZeroIsTheChiSquareOfTheEstimateOverTheDirectionsWithVariance) {
  Eigen::Vector2d a(2.0, 3.0);
  Eigen::Matrix2d C = Eigen::Vector2d(4.0, 1.0).asDiagonal();
  WaldTest w = WaldTestZero(a, C);
  EXPECT_EQ(w.dof, 2);
  EXPECT_NEAR(w.statistic, 10.0, 1e-12);
  EXPECT_NEAR(w.p_value, std::exp(-5.0), 1e-12);
  const double c = std::cos(0.5236), s = std::sin(0.5236);
  Eigen::Matrix2d R;
  R << c, -s, s, c;
  w = WaldTestZero(R * a, R * C * R.transpose());
  EXPECT_EQ(w.dof, 2);
  EXPECT_NEAR(w.statistic, 10.0, 1e-9);  // rounding of the rotation and the eigen-solver
  const Eigen::Vector2d u = Eigen::Vector2d(1.0, 1.0).normalized();
  w = WaldTestZero(a, 9.0 * u * u.transpose());
  EXPECT_EQ(w.dof, 1);
  EXPECT_NEAR(w.statistic, std::pow(u.dot(a), 2) / 9.0, 1e-12);
  EXPECT_NEAR(w.p_value, std::erfc(std::sqrt(0.5 * w.statistic)), 1e-12);
  w = WaldTestZero(a, Eigen::Matrix2d::Zero());
  EXPECT_EQ(w.dof, 0);
  EXPECT_EQ(w.p_value, 1.0);
  EXPECT_EQ(WaldTestZero(Eigen::VectorXd(), Eigen::MatrixXd()).p_value, 1.0);
  EXPECT_THROW(WaldTestZero(a, Eigen::Matrix3d::Identity()), PreconditionError);
}

// Holm by hand: sorted 0.01, 0.03, 0.04 times 3, 2, 1 = 0.03, 0.06, 0.04 -> running maximum
// 0.03, 0.06, 0.06, returned in the input order.
TEST(Statistics, HolmAdjustsStepDownWithARunningMaximum) {
  const std::vector<double> adjusted = HolmAdjust({0.04, 0.01, 0.03});
  ASSERT_EQ(adjusted.size(), 3u);
  EXPECT_DOUBLE_EQ(adjusted[0], 0.06);
  EXPECT_DOUBLE_EQ(adjusted[1], 0.03);
  EXPECT_DOUBLE_EQ(adjusted[2], 0.06);
  EXPECT_DOUBLE_EQ(HolmAdjust({0.9, 0.8})[0], 1.0);  // capped at 1
  // One candidate: no correction.
  EXPECT_DOUBLE_EQ(HolmAdjust({0.02})[0], 0.02);
}

// 20 positive differences with distinct sizes: W+ = 210, mean 105, variance 20 21 41 / 24 =
// 717.5, z = (210 - 105 - 0.5) / sqrt(717.5).
TEST(Statistics, WilcoxonSignedRankScoresByHand) {
  std::vector<double> d;
  for (int i = 1; i <= 20; ++i) d.push_back(0.1 * i);
  const PairedTest t = WilcoxonSignedRankGreater(d);
  EXPECT_EQ(t.pairs, 20);
  EXPECT_DOUBLE_EQ(t.w_plus, 210.0);
  EXPECT_NEAR(t.z, 104.5 / std::sqrt(717.5), 1e-12);
  EXPECT_LT(t.p_value, 1e-4);
  // All negative: no evidence of improvement.
  for (double& v : d) v = -v;
  EXPECT_GT(WilcoxonSignedRankGreater(d).p_value, 0.999);
  // Too few pairs: p = 1.
  EXPECT_DOUBLE_EQ(WilcoxonSignedRankGreater({1.0, 2.0, 3.0}).p_value, 1.0);
}

// Under the null (symmetric differences) the test rejects at 5 % about 5 % of the time: over
// 400 seeded samples of 100 pairs the rate's standard error is 1.1 %, so [1.5 %, 9 %] is
// about +-3.5 standard errors (allowing the normal approximation's slight conservatism).
TEST(Statistics, WilcoxonHoldsItsLevelUnderTheNull) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> noise(0.0, 1.0);
  int rejected = 0;
  for (int s = 0; s < 400; ++s) {
    std::vector<double> d(100);
    for (double& v : d) v = noise(rng);
    if (WilcoxonSignedRankGreater(d).p_value < 0.05) ++rejected;
  }
  EXPECT_GE(rejected, 6);
  EXPECT_LE(rejected, 36);
}

// The sign-flip test counted by hand: of the 2^n sign assignments on |d|, the share whose sum
// is at least the observed one.
TEST(Statistics, SignFlipTestCountsSignAssignmentsByHand) {
  // {1, 2, 3}: only all-positive reaches 6: 1 of 8.
  EXPECT_DOUBLE_EQ(SignFlipTestGreater({1.0, 2.0, 3.0}), 1.0 / 8.0);
  // {3, -1, 2} (sum 4): +3+1+2 = 6 and +3-1+2 = 4 reach it: 2 of 8.
  EXPECT_DOUBLE_EQ(SignFlipTestGreater({3.0, -1.0, 2.0}), 2.0 / 8.0);
  // {1, -1} (sum 0): 2, 0, 0 reach it, -2 does not: 3 of 4 (ties count).
  EXPECT_DOUBLE_EQ(SignFlipTestGreater({1.0, -1.0}), 3.0 / 4.0);
  // Five folds all one way is the smallest p five can give: 1 / 32 (< 0.05); four of five
  // cannot go below 2 / 32 (> 0.05) whatever the sizes.
  EXPECT_DOUBLE_EQ(SignFlipTestGreater({0.5, 1.0, 2.0, 0.1, 3.0}), 1.0 / 32.0);
  EXPECT_GT(SignFlipTestGreater({0.5, 1.0, 2.0, -0.1, 3.0}), 0.05);
  // A zero difference doubles both counts: the p is as without it.
  EXPECT_DOUBLE_EQ(SignFlipTestGreater({1.0, 2.0, 3.0, 0.0}), 1.0 / 8.0);
  EXPECT_DOUBLE_EQ(SignFlipTestGreater({}), 1.0);
  // Above 20 differences, the normal approximation: 25 ones give z = 25 / 5.
  EXPECT_NEAR(SignFlipTestGreater(std::vector<double>(25, 1.0)), NormalUpperTail(5.0), 1e-15);
}

TEST(Statistics, CorrelationOfLinearAndConstantSeries) {
  const std::vector<double> x{1, 2, 3, 4, 5};
  EXPECT_NEAR(Correlation(x, {2, 4, 6, 8, 10}), 1.0, 1e-15);
  EXPECT_NEAR(Correlation(x, {5, 4, 3, 2, 1}), -1.0, 1e-15);
  EXPECT_DOUBLE_EQ(Correlation(x, {3, 3, 3, 3, 3}), 0.0);
}

}  // namespace
}  // namespace twin::stats
