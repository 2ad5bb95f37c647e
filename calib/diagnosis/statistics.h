// The statistics of model discovery (calib/diagnosis/model_discovery.h): a chi-square tail for
// the residual test against the noise floor, a paired one-sided test of held-out residuals for
// a candidate effect, a sign-flip test of fold-level differences, Holm's step-down correction
// for the number of candidates tried, Wald's test of a candidate's size against zero, and
// correlations for the residual maps. Written from the textbook definitions (references at
// each function); no statistics library is among the project's dependencies.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace twin::stats {

/// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a), a > 0, x >= 0: the
/// series of P for x < a + 1, Legendre's continued fraction of Q otherwise (Abramowitz and
/// Stegun 6.5.29 and 6.5.31), both to 1e-14 relative.
double UpperIncompleteGammaRatio(double a, double x);

/// P(X >= x) for X chi-square with `dof` degrees of freedom (> 0): Q(dof / 2, x / 2).
double ChiSquareUpperTail(double x, double dof);

/// Standard normal upper tail P(Z >= z).
double NormalUpperTail(double z);

/// Its inverse: z with P(Z >= z) = p, for p in (0, 1) (bisection to 1e-12 in z).
double NormalUpperQuantile(double p);

/// Result of the paired test.
struct PairedTest {
  int pairs = 0;      ///< non-zero differences used
  double w_plus = 0;  ///< Wilcoxon's W+ (sum of the ranks of the positive differences)
  double z = 0;       ///< its normal score, with tie and continuity correction
  double p_value = 1; ///< one-sided: P(W+ this large | no improvement)
};

/// Wilcoxon's signed-rank test that the differences d (e.g. base minus candidate squared
/// held-out error, per point) are centred above zero, one-sided, by the normal approximation
/// with the tie correction of the variance (valid for 20 or more pairs; fewer give p = 1, i.e.
/// no evidence). Zero differences are dropped.
PairedTest WilcoxonSignedRankGreater(const std::vector<double>& d);

/// Fisher's sign-flip randomization test that the differences d (e.g. one model's held-out
/// loss less another's, summed per cross-validation fold) are centred above zero, one-sided:
/// p is the share of the 2^n sign assignments s whose sum of s_i |d_i| is at least sum(d_i)
/// (Fisher 1935, The Design of Experiments, 21; e.g. Good, Permutation Tests, 3.1). It assumes
/// only that each d_i is symmetric about zero under no difference, independently of the others.
/// Exact for n <= 20; above, the normal approximation z = sum(d) / sqrt(sum(d^2)). With n
/// differences the smallest p is 2^-n (n = 5: 0.031). Empty: p = 1.
double SignFlipTestGreater(const std::vector<double>& d);

/// Holm's step-down adjusted p-values (Holm 1979), same order as `p`: for the k-th smallest
/// (k = 1..m), max over j <= k of min(1, (m - j + 1) p_(j)). Rejecting where adjusted < alpha
/// keeps the family-wise error rate at alpha.
std::vector<double> HolmAdjust(const std::vector<double>& p);

/// Wald's test that an estimate `a` with covariance `C` is zero: W = a' C^+ a, C^+ the
/// pseudo-inverse over the eigenvalues above 1e-12 of the largest (a direction without
/// variance is one the data did not estimate and counts for nothing), against chi-square with
/// that many dof (Wald 1943; e.g. Seber and Lee, Linear Regression Analysis, 4.3). No
/// direction with variance: statistic 0, dof 0, p 1.
struct WaldTest {
  double statistic = 0;
  int dof = 0;
  double p_value = 1;
};
WaldTest WaldTestZero(const Eigen::VectorXd& a, const Eigen::MatrixXd& C);

/// Pearson's correlation of x and y (same size >= 3); 0 when either is constant.
double Correlation(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace twin::stats
