#include "calib/diagnosis/harmonic_orders.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Dense>

#include "calib/common/errors.h"

namespace twin::discovery {

// Readings closer than this count as one (a repeated pose's encoder jitter) [rad].
constexpr double kSameReading = 1e-6;

int ResolvedOrder(const std::vector<double>& q, int max_order) {
  if (q.size() < 2) return 0;
  std::vector<double> sorted = q;
  std::sort(sorted.begin(), sorted.end());
  int distinct = 1;
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i] - sorted[i - 1] > kSameReading) ++distinct;
  }
  const double range = sorted.back() - sorted.front();
  if (distinct < 3 || range <= kSameReading) return 0;
  const double resolved = M_PI * (distinct - 1) / range;
  return static_cast<int>(std::min<double>(max_order, std::floor(resolved)));
}

std::vector<double> HarmonicPower(const std::vector<Eigen::VectorXd>& residuals,
                                  const std::vector<double>& q, int max_order) {
  TWIN_REQUIRE(residuals.size() == q.size(), "residuals and readings differ in count");
  const int n = static_cast<int>(q.size());
  const int top = ResolvedOrder(q, max_order);
  std::vector<double> power(top, 0.0);
  if (top == 0) return power;
  const int dims = static_cast<int>(residuals[0].size());
  Eigen::MatrixXd E(n, dims);
  for (int i = 0; i < n; ++i) E.row(i) = residuals[i].transpose();
  const Eigen::MatrixXd centred = E.rowwise() - E.colwise().mean();
  for (int h = 1; h <= top; ++h) {
    Eigen::MatrixXd A(n, 3);
    for (int i = 0; i < n; ++i) A.row(i) << 1.0, std::sin(h * q[i]), std::cos(h * q[i]);
    const Eigen::MatrixXd coef = A.colPivHouseholderQr().solve(E);
    const Eigen::MatrixXd left = E - A * coef;
    power[h - 1] = centred.squaredNorm() - left.squaredNorm();
  }
  return power;
}

std::vector<std::vector<int>> SpectrumOrders(const std::vector<Eigen::VectorXd>& residuals,
                                             const std::vector<const MeasurementContext*>& contexts,
                                             int joints, int max_order, int per_joint) {
  return SpectrumOrdersPerJoint(std::vector<std::vector<Eigen::VectorXd>>(joints, residuals),
                                contexts, max_order, per_joint);
}

std::vector<std::vector<int>> SpectrumOrdersPerJoint(
    const std::vector<std::vector<Eigen::VectorXd>>& residuals,
    const std::vector<const MeasurementContext*>& contexts, int max_order, int per_joint) {
  const int joints = static_cast<int>(residuals.size());
  std::vector<std::vector<int>> orders(joints);
  for (int j = 0; j < joints; ++j) {
    std::vector<double> q(contexts.size());
    for (std::size_t i = 0; i < contexts.size(); ++i) q[i] = contexts[i]->q(j);
    const std::vector<double> power = HarmonicPower(residuals[j], q, max_order);
    std::vector<int> h(power.size());
    std::iota(h.begin(), h.end(), 1);
    std::stable_sort(h.begin(), h.end(), [&](int a, int b) { return power[a - 1] > power[b - 1]; });
    h.resize(std::min<std::size_t>(h.size(), per_joint));
    std::sort(h.begin(), h.end());
    orders[j] = h;
  }
  return orders;
}

std::vector<std::vector<int>> WithFundamental(std::vector<std::vector<int>> orders) {
  for (std::vector<int>& h : orders) {
    if (!h.empty() && h.front() != 1) h.insert(h.begin(), 1);
  }
  return orders;
}

}  // namespace twin::discovery
