#include "calib/identification/nonlinear_identification.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <ceres/ceres.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;

constexpr int kMaxParams = kParamsPerLink * (kMaxJoints + 1);

// Eq. 1 on scalar T: p_BE for the geometric parameters phi (ChainEndPoseT, the one FK).
template <typename T>
Vec3<T> EndPositionT(const KinematicModel& m, const T* phi, const JointVector& q) {
  T q_link[kMaxJoints];
  for (int i = 0; i < m.num_joints(); ++i) q_link[i] = T(q(i));
  return ChainEndPoseT<T>(m, phi, q_link, T(1.0)).p;
}

// phi = phi0 + SV z: the 35 parameters from the identifiable coordinates z.
template <typename T>
void ExpandParameters(const ParameterVector& phi0, const Eigen::MatrixXd& SV, const T* z, T* phi) {
  for (int i = 0; i < phi0.size(); ++i) {
    phi[i] = T(phi0(i));
    for (int j = 0; j < SV.cols(); ++j) phi[i] += SV(i, j) * z[j];
  }
}

// (I - mu mu^T / |mu|^2)(p - c): the part of p - c perpendicular to the line (eq. 14-15).
template <typename T>
Vec3<T> PerpendicularPart(const Vec3<T>& p, const Vec3<T>& c, const Vec3<T>& mu) {
  const Vec3<T> d = p - c;
  return d - mu * (d.dot(mu) / mu.squaredNorm());
}

// Eq. 13-15: the feature point p_BE(phi, q_i) of a sample servoed onto axis k lies on the line
// l_k = {c_k + lambda mu_k}, i.e. (I - mu_k mu_k^T)(p_BE - c_k) = 0. Residual (3 rows, m) with
//   phi = phi0 + SV z,  c_k = c0_k + N_k s_k,  mu_k on the unit sphere.
// Parameter blocks: z (rank), s_k (2), mu_k (3). Holds only const references to shared data.
struct AxisResidualFunctor {
  const KinematicModel& model;
  const ParameterVector& phi0;
  const Eigen::MatrixXd& SV;  // kNumParams x rank: column_scale .* identifiable_basis
  JointVector q;
  Vector3 offset;
  Vector3 c0;
  Eigen::Matrix<double, 3, 2> N;

  template <typename T>
  bool operator()(T const* const* blocks, T* residual) const {
    const T* z = blocks[0];
    const T* s = blocks[1];
    const T* mu = blocks[2];
    T phi[kMaxParams];
    ExpandParameters(phi0, SV, z, phi);
    const Vec3<T> p = EndPositionT(model, phi, q) - offset.cast<T>();
    const Vec3<T> c = c0.cast<T>() + N.col(0).cast<T>() * s[0] + N.col(1).cast<T>() * s[1];
    const Vec3<T> r = PerpendicularPart(p, c, Vec3<T>(mu[0], mu[1], mu[2]));
    for (int i = 0; i < 3; ++i) residual[i] = r(i);
    return true;
  }
};

// The scale measurement (header): w (mu_k . (p_i - c_k) / |mu_k| - t_k - z_i), 1 row [m].
// Parameter blocks: z (rank), s_k (2), mu_k (3), t_k (1).
struct DepthResidualFunctor {
  const KinematicModel& model;
  const ParameterVector& phi0;
  const Eigen::MatrixXd& SV;
  JointVector q;
  Vector3 offset;
  Vector3 c0;
  Eigen::Matrix<double, 3, 2> N;
  double depth;
  const double& weight;  // shared, so a second solve can reweight

  template <typename T>
  bool operator()(T const* const* blocks, T* residual) const {
    const T* z = blocks[0];
    const T* s = blocks[1];
    const T* mu = blocks[2];
    const T* t = blocks[3];
    T phi[kMaxParams];
    ExpandParameters(phi0, SV, z, phi);
    const Vec3<T> p = EndPositionT(model, phi, q) - offset.cast<T>();
    const Vec3<T> c = c0.cast<T>() + N.col(0).cast<T>() * s[0] + N.col(1).cast<T>() * s[1];
    const Vec3<T> m(mu[0], mu[1], mu[2]);
    residual[0] = T(weight) * ((p - c).dot(m) / m.norm() - t[0] - T(depth));
    return true;
  }
};

bool AllHaveDepth(const std::vector<AxisSample>& samples) {
  for (const AxisSample& s : samples) {
    if (!std::isfinite(s.depth)) return false;
  }
  return !samples.empty();
}

// Rows mu_k^T (J_j - J_i) for consecutive samples of each axis: how the distance between
// positions along the axis changes with the parameters (what the depths measure).
Eigen::MatrixXd DepthRows(const KinematicModel& model, const std::vector<AxisSample>& samples,
                          const std::vector<Line3>& axes) {
  std::vector<std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>>> J(axes.size());
  for (const AxisSample& s : samples) {
    J[s.axis].push_back(IdentificationJacobian(model, s.q).topRows<3>());
  }
  std::vector<Eigen::RowVectorXd> rows;
  for (size_t k = 0; k < axes.size(); ++k) {
    const Vector3 mu = axes[k].direction.normalized();
    for (size_t i = 1; i < J[k].size(); ++i) rows.push_back(mu.transpose() * (J[k][i] - J[k][i - 1]));
  }
  Eigen::MatrixXd D(rows.size(), model.num_parameters());
  for (size_t r = 0; r < rows.size(); ++r) D.row(r) = rows[r];
  return D;
}

double RmsDistance(const KinematicModel& model, const std::vector<AxisSample>& samples,
                   const std::vector<Line3>& axes) {
  double sum = 0.0;
  for (const AxisSample& s : samples) {
    const Line3& l = axes[s.axis];
    sum += PerpendicularPart<double>(AxisPoint(model, s), l.point, l.direction).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(samples.size()));
}

}  // namespace

void ValidateNonlinearIdentificationOptions(const NonlinearIdentificationOptions& o) {
  auto fail = [](const char* field, double v, const char* expected) {
    throw InputError(std::string("NonlinearIdentificationOptions.") + field,
                     std::string(expected) + ", got " + std::to_string(v));
  };
  if (o.max_iterations < 1) fail("max_iterations", o.max_iterations, "must be >= 1");
  if (!(o.function_tolerance > 0.0 && o.function_tolerance < 1.0)) {
    fail("function_tolerance", o.function_tolerance, "must be in (0, 1)");
  }
  if (!(std::isfinite(o.gradient_tolerance) && o.gradient_tolerance > 0.0)) {
    fail("gradient_tolerance", o.gradient_tolerance, "must be a positive finite number");
  }
  if (!(std::isfinite(o.parameter_tolerance) && o.parameter_tolerance > 0.0)) {
    fail("parameter_tolerance", o.parameter_tolerance, "must be a positive finite number");
  }
  if (!(o.rank_tolerance > 0.0 && o.rank_tolerance < 1.0)) {
    fail("rank_tolerance", o.rank_tolerance, "must be in (0, 1)");
  }
  if (o.loss != NonlinearLoss::kNone && o.loss != NonlinearLoss::kHuber) {
    fail("loss", static_cast<double>(o.loss), "must be kNone or kHuber");
  }
  if (o.loss == NonlinearLoss::kHuber &&
      !(std::isfinite(o.huber_scale) && o.huber_scale > 0.0)) {
    fail("huber_scale", o.huber_scale, "must be a positive finite number [m] with kHuber");
  }
}

const char* ToString(NonlinearIdentificationStatus status) {
  switch (status) {
    case NonlinearIdentificationStatus::kConverged: return "converged";
    case NonlinearIdentificationStatus::kMaxIterations: return "max_iterations";
    case NonlinearIdentificationStatus::kFailed: return "failed";
  }
  return "unknown";
}

Vector3 AxisResidual(const KinematicModel& model, const ParameterVector& phi,
                     const JointVector& q, const Vector3& point, const Vector3& direction) {
  return PerpendicularPart<double>(EndPositionT<double>(model, phi.data(), q), point, direction);
}

NonlinearIdentificationResult IdentifyNonlinear(const KinematicModel& nominal,
                                                const std::vector<AxisSample>& samples,
                                                const NonlinearIdentificationOptions& options) {
  ValidateNonlinearIdentificationOptions(options);
  const int num_axes = ValidateAxisSamples(samples);
  NonlinearIdentificationResult res;
  res.model = nominal;
  const ParameterVector phi0 = GetParameters(nominal);
  res.correction = ParameterVector::Zero(phi0.size());

  // Identifiable subspace exactly as the linearized method computes it (profiled Phi), plus
  // the depth rows when the scale is measured.
  std::vector<Line3> axes0 = FitAxes(nominal, samples);
  const bool depth = options.use_depth && AllHaveDepth(samples);
  res.depth_used = depth;
  if (depth) {
    // Orient each mu0_k so that the measured depth grows along it.
    std::vector<std::vector<std::pair<double, double>>> along(num_axes);
    for (const AxisSample& smp : samples) {
      const Line3& l = axes0[smp.axis];
      along[smp.axis].push_back({(AxisPoint(nominal, smp) - l.point).dot(l.direction), smp.depth});
    }
    for (int k = 0; k < num_axes; ++k) {
      double ms = 0, mz = 0, c = 0;
      for (const auto& [a, zz] : along[k]) { ms += a; mz += zz; }
      ms /= along[k].size();
      mz /= along[k].size();
      for (const auto& [a, zz] : along[k]) c += (a - ms) * (zz - mz);
      if (c < 0) axes0[k].direction = -axes0[k].direction;
    }
  }
  std::vector<Vector3> directions;
  for (const Line3& l : axes0) directions.push_back(l.direction);
  const MisalignedErrorStack stack = StackMisalignedErrors(nominal, samples, directions);
  std::vector<ParameterVector> invariants = LineConstraintInvariants(nominal);
  Eigen::MatrixXd Phi = ProfiledPhi(stack);
  if (depth) {
    invariants.pop_back();  // the uniform scale: measured now
    const Eigen::MatrixXd D = DepthRows(nominal, samples, axes0);
    Eigen::MatrixXd stacked(Phi.rows() + D.rows(), nominal.num_parameters());
    stacked << Phi, D;
    Phi = stacked;
  }
  res.observability =
      AnalyseObservability(Phi, nominal, options.rank_tolerance, invariants);
  const int rank = res.observability.rank;
  res.axes = axes0;
  res.rms_distance_before = RmsDistance(nominal, samples, axes0);
  res.rms_distance_after = res.rms_distance_before;
  res.z = Eigen::VectorXd::Zero(rank);
  if (rank == 0) {
    res.status = NonlinearIdentificationStatus::kFailed;
    res.reason = "no identifiable parameter combination (rank 0)";
    return res;
  }
  const Eigen::MatrixXd SV =
      res.observability.column_scale.asDiagonal() * res.observability.identifiable_basis;

  // Line blocks: s_k (point offset in the plane perpendicular to mu0_k), mu_k and, with
  // depths, t_k (the along-line position of the camera centre).
  std::vector<Eigen::Vector2d> s(num_axes, Eigen::Vector2d::Zero());
  std::vector<Vector3> mu(num_axes);
  std::vector<Eigen::Matrix<double, 3, 2>> N(num_axes);
  std::vector<double> t(num_axes, 0.0);
  std::vector<int> count(num_axes, 0);
  for (int k = 0; k < num_axes; ++k) {
    mu[k] = axes0[k].direction.normalized();
    const Vector3 any = std::abs(mu[k].x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
    N[k].col(0) = mu[k].cross(any).normalized();
    N[k].col(1) = mu[k].cross(N[k].col(0));
  }
  if (depth) {
    for (const AxisSample& smp : samples) {
      t[smp.axis] += (AxisPoint(nominal, smp) - axes0[smp.axis].point).dot(mu[smp.axis]) - smp.depth;
      ++count[smp.axis];
    }
    for (int k = 0; k < num_axes; ++k) t[k] /= count[k];
  }
  // A first guess of sigma_perpendicular / sigma_depth: ~0.02 mm of servo residual against
  // ~0.1 mm of depth from a small board (DESIGN.md corner accuracy); re-estimated below.
  double weight = options.depth_weight > 0.0 ? options.depth_weight : 0.2;

  ceres::Problem problem;
  std::vector<ceres::ResidualBlockId> depth_blocks;
  for (const AxisSample& smp : samples) {
    const int k = smp.axis;
    // Dynamic autodiff because the size of z (the rank) is only known at run time.
    auto* cost = new ceres::DynamicAutoDiffCostFunction<AxisResidualFunctor, 4>(
        new AxisResidualFunctor{nominal, phi0, SV, smp.q, smp.offset, axes0[k].point, N[k]});
    cost->AddParameterBlock(rank);
    cost->AddParameterBlock(2);
    cost->AddParameterBlock(3);
    cost->SetNumResiduals(3);
    ceres::LossFunction* loss = options.loss == NonlinearLoss::kHuber
                                    ? new ceres::HuberLoss(options.huber_scale)
                                    : nullptr;
    problem.AddResidualBlock(cost, loss, {res.z.data(), s[k].data(), mu[k].data()});
    if (depth) {
      auto* dcost = new ceres::DynamicAutoDiffCostFunction<DepthResidualFunctor, 4>(
          new DepthResidualFunctor{nominal, phi0, SV, smp.q, smp.offset, axes0[k].point, N[k],
                                   smp.depth, weight});
      dcost->AddParameterBlock(rank);
      dcost->AddParameterBlock(2);
      dcost->AddParameterBlock(3);
      dcost->AddParameterBlock(1);
      dcost->SetNumResiduals(1);
      depth_blocks.push_back(
          problem.AddResidualBlock(dcost, nullptr, {res.z.data(), s[k].data(), mu[k].data(), &t[k]}));
    }
  }
  for (int k = 0; k < num_axes; ++k) {
    problem.SetManifold(mu[k].data(), new ceres::SphereManifold<3>());
  }

  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = options.function_tolerance;
  so.gradient_tolerance = options.gradient_tolerance;
  so.parameter_tolerance = options.parameter_tolerance;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  const int n = static_cast<int>(samples.size());
  auto depth_rms = [&]() {
    double sum = 0.0;
    for (ceres::ResidualBlockId id : depth_blocks) {
      double r = 0.0;
      problem.EvaluateResidualBlock(id, false, nullptr, &r, nullptr);
      sum += r * r;
    }
    return std::sqrt(sum / std::max<int>(1, n)) / weight;
  };
  if (depth && options.depth_weight <= 0.0 && summary.IsSolutionUsable()) {
    // Variance components: per-component perpendicular sigma (2 dof per sample, 4 per line)
    // against depth sigma (1 dof per sample, 1 per axis offset), then solve again.
    std::vector<Line3> lines = axes0;
    for (int k = 0; k < num_axes; ++k) {
      lines[k].direction = mu[k].normalized();
      lines[k].point = axes0[k].point + N[k] * s[k];
    }
    const KinematicModel m1 = WithParameters(nominal, phi0 + SV * res.z);
    const double rms_perp = RmsDistance(m1, samples, lines);
    const double sigma_perp =
        rms_perp * std::sqrt(static_cast<double>(n) / std::max(1, 2 * n - 4 * num_axes));
    const double d = depth_rms();
    const double sigma_depth =
        d * std::sqrt(static_cast<double>(n) / std::max(1, n - num_axes));
    if (sigma_perp > 0.0 && sigma_depth > 0.0) {
      weight = std::clamp(sigma_perp / sigma_depth, 1e-3, 1e3);
      ceres::Solve(so, &problem, &summary);
    }
  }
  res.depth_weight = depth ? weight : 0.0;
  if (depth) res.rms_depth_residual = depth_rms();

  res.brief_report = summary.BriefReport();
  res.reason = summary.message;
  res.iterations = static_cast<int>(summary.iterations.size()) - 1;
  switch (summary.termination_type) {
    case ceres::CONVERGENCE: res.status = NonlinearIdentificationStatus::kConverged; break;
    case ceres::NO_CONVERGENCE: res.status = NonlinearIdentificationStatus::kMaxIterations; break;
    default: res.status = NonlinearIdentificationStatus::kFailed; break;
  }
  if (res.status == NonlinearIdentificationStatus::kFailed) {
    res.z.setZero();
    return res;
  }
  res.correction = SV * res.z;
  res.model = WithParameters(nominal, phi0 + res.correction);
  for (int k = 0; k < num_axes; ++k) {
    res.axes[k].direction = mu[k].normalized();
    res.axes[k].point = axes0[k].point + N[k] * s[k];
  }
  res.rms_distance_after = RmsDistance(res.model, samples, res.axes);
  const ParameterVector v = LineConstraintInvariants(nominal).back();
  res.scale = 1.0 + v.dot(res.correction) / v.squaredNorm();
  return res;
}

}  // namespace twin
