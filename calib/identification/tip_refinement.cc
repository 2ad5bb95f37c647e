#include "calib/identification/tip_refinement.h"

#include <cmath>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

constexpr int kMinTipContacts = 4;

// Contact residual (3): X_B1F1 (t1 + a0 u + a1 v) - (R p2 + p), p2 = X_B2F2 (t2 + dt2), with
// the rotation R of X_B1B2 as a quaternion (Ceres order w, x, y, z).
struct ContactResidual {
  Transform X_B1F1, X_B2F2;
  Vector3 t1, t2, u, v;

  template <typename T>
  bool operator()(const T* q, const T* p, const T* a, const T* dt2, T* r) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const V3 tip1 = t1.cast<T>() + a[0] * u.cast<T>() + a[1] * v.cast<T>();
    const V3 p1 = X_B1F1.linear().cast<T>() * tip1 + X_B1F1.translation().cast<T>();
    const V3 tip2 = t2.cast<T>() + V3(dt2[0], dt2[1], dt2[2]);
    const V3 p2 = X_B2F2.linear().cast<T>() * tip2 + X_B2F2.translation().cast<T>();
    T p2_arr[3] = {p2(0), p2(1), p2(2)};
    T rp2[3];
    ceres::UnitQuaternionRotatePoint(q, p2_arr, rp2);
    for (int k = 0; k < 3; ++k) r[k] = p1(k) - (rp2[k] + p[k]);
    return true;
  }
};

bool Finite(const Transform& X) { return X.matrix().allFinite(); }

}  // namespace

void TipRefinementOptions::Validate() const {
  // No user sets these (the handclasp section reaches none of them): a bad value is our bug.
  TWIN_REQUIRE(min_relative_singular_value >= 0 && min_relative_singular_value < 1,
               "TipRefinementOptions.min_relative_singular_value must be in [0, 1), got " +
                   std::to_string(min_relative_singular_value));
  TWIN_REQUIRE(rotation_scale_m > 0 && std::isfinite(rotation_scale_m),
               "TipRefinementOptions.rotation_scale_m must be > 0, got " +
                   std::to_string(rotation_scale_m));
  TWIN_REQUIRE(max_iterations >= 1, "TipRefinementOptions.max_iterations must be >= 1, got " +
                                        std::to_string(max_iterations));
}

TipRefinementResult RefineBaseAndTips(const std::vector<Transform>& X_B1F1,
                                      const std::vector<Transform>& X_B2F2,
                                      const Vector3& t1_F1, const Vector3& t2_F2,
                                      const Vector3& tip1_axis_F1,
                                      const Transform& X_B1B2_initial,
                                      const TipRefinementOptions& options) {
  options.Validate();
  // The flange poses are forward kinematics of encoder readings, the tips and the start come
  // from validated models and a base calibration: none is a user's number, so a mismatch or
  // a non-finite value is our bug.
  TWIN_REQUIRE(X_B1F1.size() == X_B2F2.size(),
               std::to_string(X_B1F1.size()) + " flange poses of robot 1 but " +
                   std::to_string(X_B2F2.size()) + " of robot 2");
  for (size_t i = 0; i < X_B1F1.size(); ++i) {
    TWIN_REQUIRE(Finite(X_B1F1[i]) && Finite(X_B2F2[i]),
                 "non-finite flange pose at contact " + std::to_string(i));
  }
  TWIN_REQUIRE(t1_F1.allFinite() && t2_F2.allFinite() && Finite(X_B1B2_initial) &&
                   tip1_axis_F1.allFinite() && tip1_axis_F1.norm() > 1e-9,
               "tips, tip axis and initial transform must be finite (and the axis non-zero)");
  TipRefinementResult out;
  const int n = static_cast<int>(X_B1F1.size());
  if (n < kMinTipContacts) {
    out.reason = "tip refinement needs at least " + std::to_string(kMinTipContacts) +
                 " contacts, got " + std::to_string(n);
    return out;
  }
  // Gauge: dt1 perpendicular to tip 1's axis (see the header).
  const Vector3 w = tip1_axis_F1.normalized();
  Vector3 u = w.cross(Vector3::UnitX());
  if (u.norm() < 0.1) u = w.cross(Vector3::UnitY());
  u.normalize();
  const Vector3 v = w.cross(u);

  const Eigen::Quaterniond q0(X_B1B2_initial.linear());
  double q[4] = {q0.w(), q0.x(), q0.y(), q0.z()};
  Vector3 p = X_B1B2_initial.translation();
  double a[2] = {0.0, 0.0};
  Vector3 dt2 = Vector3::Zero();

  ceres::Problem problem;
  for (int i = 0; i < n; ++i) {
    auto* cost = new ceres::AutoDiffCostFunction<ContactResidual, 3, 4, 3, 2, 3>(
        new ContactResidual{X_B1F1[i], X_B2F2[i], t1_F1, t2_F2, u, v});
    problem.AddResidualBlock(cost, nullptr, q, p.data(), a, dt2.data());
  }
  problem.SetManifold(q, new ceres::QuaternionManifold());

  const auto rms = [&]() {
    double cost = 0.0;
    problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
    return std::sqrt(2.0 * cost / n);
  };
  out.rms_residual_before_m = rms();

  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-14;
  so.parameter_tolerance = 1e-14;
  so.gradient_tolerance = 1e-16;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size());

  // Conditioning and covariance from the Jacobian at the solution (tangent space: 3 rotation,
  // 3 translation, 2 + 3 tip coordinates).
  ceres::CRSMatrix crs;
  std::vector<double> residuals;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, &residuals, nullptr, &crs);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) J(r, crs.cols[k]) = crs.values[k];
  }
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(J.cols());
  // Ceres' QuaternionManifold tangent is half the rotation vector; the rotation columns are
  // expressed per rotation_scale_m of arc, so that all columns are lengths.
  for (int c = 0; c < 3; ++c) scale(c) = 1.0 / (2.0 * options.rotation_scale_m);
  const Eigen::MatrixXd Js = J * scale.asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js);
  const Eigen::VectorXd s = svd.singularValues();
  out.relative_singular_value = s(s.size() - 1) / s(0);
  if (!summary.IsSolutionUsable()) {
    out.reason = "the solver failed: " + summary.message;
    return out;
  }
  if (out.relative_singular_value < options.min_relative_singular_value) {
    out.reason = "the tip offsets cannot be separated from the base translation: relative "
                 "singular value " + std::to_string(out.relative_singular_value) + " < " +
                 std::to_string(options.min_relative_singular_value) +
                 " (the tip orientations vary too little between the contacts)";
    return out;
  }
  const Eigen::Map<const Eigen::VectorXd> res(residuals.data(), residuals.size());
  const int dof = static_cast<int>(res.size()) - 11;
  const double s2 = dof > 0 ? res.squaredNorm() / dof : 0.0;
  const Eigen::MatrixXd cov = s2 * (J.transpose() * J).inverse();
  Eigen::Matrix<double, 3, 2> B;
  B << u, v;
  const Matrix3 c1 = B * cov.block<2, 2>(6, 6) * B.transpose();
  out.sigma_dt1_F1 = c1.diagonal().cwiseSqrt();
  out.sigma_dt2_F2 = cov.block<3, 3>(8, 8).diagonal().cwiseSqrt();

  out.ok = true;
  out.X_B1B2 = Transform::Identity();
  out.X_B1B2.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  out.X_B1B2.translation() = p;
  out.dt1_F1 = a[0] * u + a[1] * v;
  out.dt2_F2 = dt2;
  out.rms_residual_m = rms();
  return out;
}

}  // namespace twin
