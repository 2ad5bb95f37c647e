#include "calib/identification/identification_covariance.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "calib/model/parameters.h"

namespace twin {

IdentificationCovariance EstimateIdentificationCovariance(
    const KinematicModel& nominal, const std::vector<AxisSample>& samples,
    const NonlinearIdentificationResult& result) {
  IdentificationCovariance out;
  const int rank = result.observability.rank;
  const int num_axes = static_cast<int>(result.axes.size());
  if (result.status == NonlinearIdentificationStatus::kFailed || rank < 1 ||
      result.z.size() != rank || samples.empty()) {
    out.reason = "the identification failed or identified nothing";
    return out;
  }
  const bool depth = result.depth_used;
  const double w = result.depth_weight;
  const Eigen::MatrixXd SV =
      result.observability.column_scale.asDiagonal() * result.observability.identifiable_basis;
  const ParameterVector phi0 = GetParameters(nominal);

  // Local line coordinates at the solution: c = c* + N s, mu = normalize(mu* + N a).
  std::vector<Eigen::Matrix<double, 3, 2>> N(num_axes);
  for (int k = 0; k < num_axes; ++k) {
    const Vector3 mu = result.axes[k].direction.normalized();
    const Vector3 any = std::abs(mu.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
    N[k].col(0) = mu.cross(any).normalized();
    N[k].col(1) = mu.cross(N[k].col(0));
  }
  const int per_axis = depth ? 5 : 4;
  const int n = rank + per_axis * num_axes;
  const int rows_per_sample = depth ? 4 : 3;
  const int m = rows_per_sample * static_cast<int>(samples.size());

  // Axis offsets t_k at the solution: the least-squares optimum given the rest.
  std::vector<double> t0(num_axes, 0.0);
  if (depth) {
    std::vector<int> count(num_axes, 0);
    for (const AxisSample& s : samples) {
      const Line3& l = result.axes[s.axis];
      t0[s.axis] += (AxisPoint(result.model, s) - l.point).dot(l.direction.normalized()) -
                    s.depth;
      ++count[s.axis];
    }
    for (int k = 0; k < num_axes; ++k) t0[k] /= std::max(1, count[k]);
  }

  auto residuals = [&](const Eigen::VectorXd& x) {
    const KinematicModel model = WithParameters(nominal, phi0 + SV * (result.z + x.head(rank)));
    Eigen::VectorXd r(m);
    int row = 0;
    for (const AxisSample& s : samples) {
      const int k = s.axis;
      const Eigen::VectorXd xa = x.segment(rank + per_axis * k, per_axis);
      const Vector3 c = result.axes[k].point + N[k] * xa.head<2>();
      const Vector3 mu = (result.axes[k].direction.normalized() + N[k] * xa.segment<2>(2))
                             .normalized();
      const Vector3 d = AxisPoint(model, s) - c;
      r.segment<3>(row) = d - mu * d.dot(mu);
      row += 3;
      if (depth) r(row++) = w * (d.dot(mu) - (t0[k] + xa(4)) - s.depth);
    }
    return r;
  };

  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd r0 = residuals(x0);
  // Central differences: steps of 1e-6 (m or rad) keep the truncation error (h^2 times the
  // third derivative, ~1e-12 relative) and the rounding error (1e-16 / h) far below 1e-6.
  const double h = 1e-6;
  Eigen::MatrixXd J(m, n);
  for (int j = 0; j < n; ++j) {
    Eigen::VectorXd xp = x0, xm = x0;
    xp(j) += h;
    xm(j) -= h;
    J.col(j) = (residuals(xp) - residuals(xm)) / (2 * h);
  }
  // A perpendicular part has 2 independent rows (its component along mu is zero).
  const int independent = (depth ? 3 : 2) * static_cast<int>(samples.size());
  out.redundancy = independent - n;
  if (out.redundancy < 1) {
    out.reason = "no redundancy (" + std::to_string(independent) + " independent residuals, " +
                 std::to_string(n) + " unknowns)";
    return out;
  }
  const double s2 = r0.squaredNorm() / out.redundancy;
  out.residual_sigma = std::sqrt(s2);
  const Eigen::MatrixXd JtJ = J.transpose() * J;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(JtJ);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) {
    out.reason = "J^T J is singular";
    return out;
  }
  const Eigen::MatrixXd cov = s2 * ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  out.z = cov.topLeftCorner(rank, rank);
  out.sigma_z = out.z.diagonal().cwiseMax(0.0).cwiseSqrt();
  out.sigma_parameters = (SV * out.z * SV.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  out.ok = true;
  return out;
}

}  // namespace twin
