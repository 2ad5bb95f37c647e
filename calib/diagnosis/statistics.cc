#include "calib/diagnosis/statistics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>

#include <Eigen/Eigenvalues>

#include "calib/common/errors.h"

namespace twin::stats {
namespace {

constexpr double kEps = 1e-14;
constexpr int kMaxTerms = 10000;

// P(a, x) by its power series: x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a + 1)...(a + n)).
double LowerSeries(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < kMaxTerms; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * kEps) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Q(a, x) by the continued fraction e^-x x^a / Gamma(a) * 1/(x + 1 - a - 1(1 - a)/(x + 3 - a
// - ...)), evaluated with the modified Lentz method.
double UpperFraction(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int n = 1; n < kMaxTerms; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEps) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double UpperIncompleteGammaRatio(double a, double x) {
  TWIN_REQUIRE(a > 0.0 && x >= 0.0, "UpperIncompleteGammaRatio: a = " + std::to_string(a) +
                                        ", x = " + std::to_string(x));
  if (x == 0.0) return 1.0;
  if (x < a + 1.0) return std::clamp(1.0 - LowerSeries(a, x), 0.0, 1.0);
  return std::clamp(UpperFraction(a, x), 0.0, 1.0);
}

double ChiSquareUpperTail(double x, double dof) {
  TWIN_REQUIRE(dof > 0.0, "ChiSquareUpperTail: dof " + std::to_string(dof));
  return UpperIncompleteGammaRatio(0.5 * dof, std::max(0.0, 0.5 * x));
}

WaldTest WaldTestZero(const Eigen::VectorXd& a, const Eigen::MatrixXd& C) {
  TWIN_REQUIRE(C.rows() == a.size() && C.cols() == a.size(),
               "WaldTestZero: a covariance of " + std::to_string(C.rows()) + " x " +
                   std::to_string(C.cols()) + " for an estimate of " +
                   std::to_string(a.size()));
  WaldTest t;
  if (a.size() == 0) return t;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (C + C.transpose()));
  const double largest = eig.eigenvalues().cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) return t;
  for (int k = 0; k < a.size(); ++k) {
    const double lambda = eig.eigenvalues()(k);
    if (lambda <= 1e-12 * largest) continue;
    const double along = eig.eigenvectors().col(k).dot(a);
    t.statistic += along * along / lambda;
    ++t.dof;
  }
  t.p_value = ChiSquareUpperTail(t.statistic, t.dof);
  return t;
}

double NormalUpperTail(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

double NormalUpperQuantile(double p) {
  TWIN_REQUIRE(p > 0.0 && p < 1.0, "NormalUpperQuantile: p = " + std::to_string(p));
  double lo = -40.0, hi = 40.0;  // the tail is decreasing in z
  while (hi - lo > 1e-12) {
    const double mid = 0.5 * (lo + hi);
    (NormalUpperTail(mid) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

PairedTest WilcoxonSignedRankGreater(const std::vector<double>& d) {
  std::vector<double> nz;
  for (double v : d) {
    if (v != 0.0 && std::isfinite(v)) nz.push_back(v);
  }
  PairedTest t;
  t.pairs = static_cast<int>(nz.size());
  const int n = t.pairs;
  if (n == 0) return t;
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(nz[a]) < std::abs(nz[b]); });
  // Mid-ranks of tied |d|, and the tie term sum (t^3 - t) / 48 of the variance.
  double tie_term = 0.0;
  for (int i = 0; i < n;) {
    int j = i;
    while (j + 1 < n && std::abs(nz[order[j + 1]]) == std::abs(nz[order[i]])) ++j;
    const double rank = 0.5 * (i + j) + 1.0;
    for (int k = i; k <= j; ++k) {
      if (nz[order[k]] > 0.0) t.w_plus += rank;
    }
    const double tied = j - i + 1;
    tie_term += (tied * tied * tied - tied) / 48.0;
    i = j + 1;
  }
  const double mean = n * (n + 1.0) / 4.0;
  const double var = n * (n + 1.0) * (2.0 * n + 1.0) / 24.0 - tie_term;
  if (n < 20 || var <= 0.0) return t;  // too few pairs for the approximation: no evidence
  t.z = (t.w_plus - mean - 0.5) / std::sqrt(var);
  t.p_value = NormalUpperTail(t.z);
  return t;
}

double SignFlipTestGreater(const std::vector<double>& d) {
  const int n = static_cast<int>(d.size());
  if (n == 0) return 1.0;
  double observed = 0.0, sum_squares = 0.0;
  for (double v : d) {
    observed += v;
    sum_squares += v * v;
  }
  if (n > 20) {
    return sum_squares > 0.0 ? NormalUpperTail(observed / std::sqrt(sum_squares)) : 1.0;
  }
  // A sum equal to the observed one up to rounding counts as at least it.
  const double slack = 1e-12 * std::sqrt(sum_squares) * n;
  std::uint64_t at_least = 0;
  const std::uint64_t assignments = std::uint64_t{1} << n;
  for (std::uint64_t mask = 0; mask < assignments; ++mask) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += (mask >> i & 1u) ? -std::abs(d[i]) : std::abs(d[i]);
    if (sum >= observed - slack) ++at_least;
  }
  return static_cast<double>(at_least) / static_cast<double>(assignments);
}

std::vector<double> HolmAdjust(const std::vector<double>& p) {
  const int m = static_cast<int>(p.size());
  std::vector<int> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return p[a] < p[b]; });
  std::vector<double> adjusted(m, 1.0);
  double running = 0.0;
  for (int k = 0; k < m; ++k) {
    running = std::max(running, std::min(1.0, (m - k) * p[order[k]]));
    adjusted[order[k]] = running;
  }
  return adjusted;
}

double Correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 3) return 0.0;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  if (sxx <= 0.0 || syy <= 0.0) return 0.0;
  return sxy / std::sqrt(sxx * syy);
}

}  // namespace twin::stats
