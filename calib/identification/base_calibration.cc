#include "calib/identification/base_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include <Eigen/Dense>
#include <ceres/ceres.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

constexpr int kMinContacts = 4;  // paper section 2.2: 4 handclasp contacts determine X_B1B2

std::string Fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

// Wraps an angle to (-pi, pi].
double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

// Centred N x 3 matrix of a point cloud.
Eigen::MatrixX3d Centred(const std::vector<Vector3>& p, Vector3* mean) {
  Eigen::MatrixX3d m(p.size(), 3);
  for (size_t i = 0; i < p.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  *mean = m.colwise().mean().transpose();
  m.rowwise() -= mean->transpose();
  return m;
}

// Singular values (descending) of a centred N x 3 cloud, as square roots of the eigenvalues of
// its 3 x 3 scatter matrix.
Vector3 SingularValues(const Eigen::MatrixX3d& Q) {
  const Matrix3 scatter = Q.transpose() * Q;
  const Vector3 ev = Eigen::SelfAdjointEigenSolver<Matrix3>(scatter, Eigen::EigenvaluesOnly)
                         .eigenvalues();  // ascending
  return Vector3(ev(2), ev(1), ev(0)).cwiseMax(0.0).cwiseSqrt();
}

double RmsResidual(const std::vector<Vector3>& p_B1, const std::vector<Vector3>& p_B2,
                   const Transform& X_B1B2) {
  double sum = 0.0;
  for (size_t i = 0; i < p_B1.size(); ++i) sum += (p_B1[i] - X_B1B2 * p_B2[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(p_B1.size()));
}

// Translation of eq. 12, the mean of p_B1 - R p_B2 over all N contacts (the paper writes N = 4).
Transform WithTranslation(const Matrix3& R_B1B2, const Vector3& mean_B1, const Vector3& mean_B2) {
  Transform X = Transform::Identity();
  X.linear() = R_B1B2;
  X.translation() = mean_B1 - R_B1B2 * mean_B2;
  return X;
}

double RotationAngle(const Matrix3& R_a, const Matrix3& R_b) {
  return Eigen::AngleAxisd(R_a.transpose() * R_b).angle();
}

// Floor-wall rotation of eq. 17 minus the preliminary rotation (eq. 7), the 9 terms of the cost
// J of eq. 18/20:  R(mu, nu, rho, sigma) = [-sigma nu, -sigma mu, -rho;
//                                           rho nu,    rho mu,   -sigma;
//                                           mu,        -nu,       0],
// with mu = cos(alpha), nu = sin(alpha), rho = cos(beta), sigma = sin(beta). Parameterizing by
// the angles satisfies the constraints mu^2 + nu^2 = 1, rho^2 + sigma^2 = 1 of eq. 21
// identically, so LM solves the stationarity conditions of eq. 21 without multipliers.
struct FloorWallResidual {
  explicit FloorWallResidual(const Matrix3& R_prelim) : R_prelim_(R_prelim) {}

  template <typename T>
  bool operator()(const T* const alpha_beta, T* residual) const {
    using std::cos;
    using std::sin;
    const T mu = cos(alpha_beta[0]), nu = sin(alpha_beta[0]);
    const T rho = cos(alpha_beta[1]), sigma = sin(alpha_beta[1]);
    const T R[9] = {-sigma * nu, -sigma * mu, -rho,   //
                    rho * nu,    rho * mu,    -sigma,  //
                    mu,          -nu,         T(0.0)};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) residual[3 * r + c] = R[3 * r + c] - R_prelim_(r, c);
    return true;
  }

 private:
  const Matrix3 R_prelim_;
};

Matrix3 FloorWallRotation(double alpha, double beta) {
  // eq. 16: Rot(Z, beta) Rot(Y, -90 deg) Rot(Z, alpha).
  return (Eigen::AngleAxisd(beta, Vector3::UnitZ()) * Eigen::AngleAxisd(-kPi / 2, Vector3::UnitY()) *
          Eigen::AngleAxisd(alpha, Vector3::UnitZ()))
      .toRotationMatrix();
}

struct RefinedRotation {
  bool ok = false;
  std::string reason;
  Matrix3 R = Matrix3::Identity();
};

// Floor-floor, eq. 10-11 (closed form).
RefinedRotation FloorFloor(const Matrix3& Rp) {
  const double c = Rp(0, 0) + Rp(1, 1), s = Rp(1, 0) - Rp(0, 1);  // n_x + o_y, n_y - o_x
  const double norm = std::hypot(c, s);
  RefinedRotation out;
  if (norm < 1e-9) {
    out.reason = "floor-floor refinement (eq. 10) undefined: n_x + o_y and n_y - o_x of the "
                 "preliminary rotation are both ~0; the installation is not floor-floor";
    return out;
  }
  out.R << c / norm, -s / norm, 0, s / norm, c / norm, 0, 0, 0, 1;  // eq. 11
  out.ok = true;
  return out;
}

// Floor-ceiling, eq. 29-30 (closed form).
RefinedRotation FloorCeiling(const Matrix3& Rp) {
  const double c = Rp(0, 0) - Rp(1, 1), s = Rp(1, 0) + Rp(0, 1);  // n_x - o_y, n_y + o_x
  const double norm = std::hypot(c, s);
  RefinedRotation out;
  if (norm < 1e-9) {
    out.reason = "floor-ceiling refinement (eq. 29) undefined: n_x - o_y and n_y + o_x of the "
                 "preliminary rotation are both ~0; the installation is not floor-ceiling";
    return out;
  }
  out.R << c / norm, s / norm, 0, s / norm, -c / norm, 0, 0, 0, -1;  // eq. 30
  out.ok = true;
  return out;
}

// Floor-wall, eq. 17-21, solved with Ceres LM from the angles of the orthonormalized rotation
// (plus three shifted starts, keeping the lowest cost, against local minima of eq. 18).
RefinedRotation FloorWall(const Matrix3& Rp, const Matrix3& R_ortho,
                          const BaseCalibrationOptions& options) {
  // Initial angles read off eq. 17: R(2,0) = mu, R(2,1) = -nu, R(0,2) = -rho, R(1,2) = -sigma.
  const double alpha0 = std::atan2(-R_ortho(2, 1), R_ortho(2, 0));
  const double beta0 = std::atan2(-R_ortho(1, 2), -R_ortho(0, 2));

  ceres::Solver::Options solver_options;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.lm_max_iterations;
  solver_options.function_tolerance = options.lm_function_tolerance;
  solver_options.parameter_tolerance = options.lm_parameter_tolerance;
  solver_options.gradient_tolerance = 1e-16;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  RefinedRotation best;
  double best_cost = std::numeric_limits<double>::infinity();
  std::string last_failure;
  const double shifts[4][2] = {{0, 0}, {kPi, 0}, {0, kPi}, {kPi, kPi}};
  for (const auto& shift : shifts) {
    double alpha_beta[2] = {alpha0 + shift[0], beta0 + shift[1]};
    ceres::Problem problem;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<FloorWallResidual, 9, 2>(new FloorWallResidual(Rp)),
        nullptr, alpha_beta);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    if (summary.termination_type != ceres::CONVERGENCE) {
      last_failure = summary.message;
      continue;
    }
    if (summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best.ok = true;
      best.R = FloorWallRotation(alpha_beta[0], alpha_beta[1]);
    }
  }
  if (!best.ok) {
    best.R = R_ortho;
    best.reason = "floor-wall LM (eq. 21) did not converge in " +
                  std::to_string(options.lm_max_iterations) + " iterations: " + last_failure;
  }
  return best;
}

std::string SingularValuesText(const Vector3& sv) {
  return "(" + Fmt(sv(0)) + ", " + Fmt(sv(1)) + ", " + Fmt(sv(2)) + ") m";
}

// The contacts are forward kinematics of encoder readings through validated models, never a
// user's numbers: a non-finite one is our bug.
void CheckFinite(const std::vector<Vector3>& p, const char* name) {
  for (size_t i = 0; i < p.size(); ++i) {
    if (!p[i].allFinite()) {
      std::ostringstream os;
      os << name << "[" << i << "] = (" << p[i].transpose() << "): contact coordinates must be "
         << "finite";
      FailPrecondition("finite contacts", os.str(), __FILE__, __LINE__);
    }
  }
}

// ZYZ angles by eq. 32, with phi := 0 when `degenerate` (theta ~ 0 or pi).
Vector3 ZyzImpl(const Matrix3& R, bool degenerate) {
  const Vector3 n = R.col(0), o = R.col(1), a = R.col(2);
  if (degenerate) {
    return Vector3(0.0, WrapAngle(std::atan2(a.x(), a.z())), WrapAngle(std::atan2(n.y(), o.y())));
  }
  const double phi = std::atan2(a.y(), a.x());
  const double sp = std::sin(phi), cp = std::cos(phi);
  const double theta = std::atan2(cp * a.x() + sp * a.y(), a.z());
  const double psi = std::atan2(-sp * n.x() + cp * n.y(), -sp * o.x() + cp * o.y());
  return Vector3(WrapAngle(phi), theta, WrapAngle(psi));
}

bool ZyzDegenerate(const Matrix3& R, double tol_rad) {
  // sin(theta) = |(a_x, a_y)|; theta within tol of 0 or pi.
  return std::hypot(R(0, 2), R(1, 2)) < std::sin(std::min(tol_rad, kPi / 2));
}

}  // namespace

const char* ToString(BaseConstraint constraint) {
  switch (constraint) {
    case BaseConstraint::kFloorFloor: return "floor-floor";
    case BaseConstraint::kFloorWall: return "floor-wall";
    case BaseConstraint::kFloorCeiling: return "floor-ceiling";
    case BaseConstraint::kGeneral: return "general";
  }
  return "unknown";
}

const char* ToString(BaseCalibrationResult::Status status) {
  using S = BaseCalibrationResult::Status;
  switch (status) {
    case S::kSuccess: return "kSuccess";
    case S::kTooFewPoints: return "kTooFewPoints";
    case S::kDegenerate: return "kDegenerate";
    case S::kNotConverged: return "kNotConverged";
  }
  return "unknown";
}

void BaseCalibrationOptions::Validate() const {
  // No user sets these (the handclasp section reaches none of them): a bad value is our bug.
  const auto check = [](bool ok, const char* field, double value, const char* expected) {
    if (!ok) {
      FailPrecondition("valid BaseCalibrationOptions",
                       std::string("BaseCalibrationOptions.") + field + " must be " + expected +
                           ", got " + Fmt(value),
                       __FILE__, __LINE__);
    }
  };
  check(std::isfinite(collinear_ratio_min) && collinear_ratio_min > 0 && collinear_ratio_min < 1,
        "collinear_ratio_min", collinear_ratio_min, "in (0, 1)");
  check(std::isfinite(coplanar_ratio_min) && coplanar_ratio_min > 0 && coplanar_ratio_min < 1,
        "coplanar_ratio_min", coplanar_ratio_min, "in (0, 1)");
  check(std::isfinite(recommended_side_m) && recommended_side_m > 0, "recommended_side_m",
        recommended_side_m, "> 0");
  check(std::isfinite(side_warn_fraction) && side_warn_fraction > 0 && side_warn_fraction <= 1,
        "side_warn_fraction", side_warn_fraction, "in (0, 1]");
  check(std::isfinite(flatness_warn_ratio) && flatness_warn_ratio >= 0 && flatness_warn_ratio <= 1,
        "flatness_warn_ratio", flatness_warn_ratio, "in [0, 1]");
  check(std::isfinite(installation_mismatch_warn_rad) && installation_mismatch_warn_rad > 0,
        "installation_mismatch_warn_rad", installation_mismatch_warn_rad, "> 0");
  check(lm_max_iterations > 0, "lm_max_iterations", lm_max_iterations, "> 0");
  check(std::isfinite(lm_function_tolerance) && lm_function_tolerance > 0,
        "lm_function_tolerance", lm_function_tolerance, "> 0");
  check(std::isfinite(lm_parameter_tolerance) && lm_parameter_tolerance > 0,
        "lm_parameter_tolerance", lm_parameter_tolerance, "> 0");
}

Matrix3 NearestRotation(const Matrix3& M) {
  // eq. 3: argmin_R ||R - M||_F over SO(3) = U diag(1, 1, det(U V^T)) V^T.
  const Eigen::JacobiSVD<Matrix3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 D = Matrix3::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

Matrix3 RotationFromZyz(const Vector3& zyz) {
  // eq. 31.
  return (Eigen::AngleAxisd(zyz(0), Vector3::UnitZ()) * Eigen::AngleAxisd(zyz(1), Vector3::UnitY()) *
          Eigen::AngleAxisd(zyz(2), Vector3::UnitZ()))
      .toRotationMatrix();
}

Vector3 ZyzFromRotation(const Matrix3& R, double degenerate_tol_rad) {
  return ZyzImpl(R, ZyzDegenerate(R, degenerate_tol_rad));
}

BaseFrameError CompareBaseFrames(const Transform& estimate, const Transform& truth,
                                 double zyz_degenerate_rad) {
  BaseFrameError e;
  // eq. 34.
  e.e_tran_mm = 1e3 * (estimate.translation() - truth.translation()).cwiseAbs().maxCoeff();
  // eq. 33 with the degeneracy rule of eq. 32 applied to both rotations alike.
  const bool degenerate = ZyzDegenerate(estimate.linear(), zyz_degenerate_rad) ||
                          ZyzDegenerate(truth.linear(), zyz_degenerate_rad);
  const Vector3 d = ZyzImpl(estimate.linear(), degenerate) - ZyzImpl(truth.linear(), degenerate);
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(WrapAngle(d(i))));
  e.e_rot_deg = RadToDeg(worst);
  return e;
}

BaseCalibrationResult CalibrateBaseFrame(const std::vector<Vector3>& p_B1,
                                         const std::vector<Vector3>& p_B2,
                                         BaseConstraint constraint,
                                         const BaseCalibrationOptions& options) {
  options.Validate();
  TWIN_REQUIRE(p_B1.size() == p_B2.size(),
               "p_B1 and p_B2 must hold the same contacts, got " + std::to_string(p_B1.size()) +
                   " and " + std::to_string(p_B2.size()) + " points");
  CheckFinite(p_B1, "p_B1");
  CheckFinite(p_B2, "p_B2");

  using Status = BaseCalibrationResult::Status;
  BaseCalibrationResult result;
  const size_t n = p_B1.size();
  if (n < static_cast<size_t>(kMinContacts)) {
    result.status = Status::kTooFewPoints;
    result.reason = "base calibration needs at least " + std::to_string(kMinContacts) +
                    " handclasp contacts forming a triangular pyramid (paper section 3), got " +
                    std::to_string(n);
    return result;
  }

  Vector3 mean_B1, mean_B2;
  const Eigen::MatrixX3d Q1 = Centred(p_B1, &mean_B1);
  const Eigen::MatrixX3d Q2 = Centred(p_B2, &mean_B2);

  // Degeneracy: singular values of both centred clouds (equal without noise) relative to sigma1.
  const Vector3 sv2 = SingularValues(Q2);
  const Vector3 sv1 = SingularValues(Q1);
  result.singular_values_m = sv2;
  for (const auto& [sv, name] : {std::pair<Vector3, const char*>{sv2, "p_B2"}, {sv1, "p_B1"}}) {
    const double s1 = std::max(sv(0), std::numeric_limits<double>::min());
    if (sv(1) / s1 < options.collinear_ratio_min) {
      result.status = Status::kDegenerate;
      result.reason = std::string("contacts are (nearly) collinear: singular values of the "
                                  "centred ") + name + " cloud are " + SingularValuesText(sv) +
                      ", sigma2/sigma1 = " + Fmt(sv(1) / s1) + " < collinear_ratio_min = " +
                      Fmt(options.collinear_ratio_min) +
                      "; teach P1..P3 as a triangle and P4 off its plane (paper section 3)";
      return result;
    }
    if (sv(2) / s1 < options.coplanar_ratio_min) {
      result.status = Status::kDegenerate;
      result.reason = std::string("contacts are (nearly) coplanar: singular values of the "
                                  "centred ") + name + " cloud are " + SingularValuesText(sv) +
                      ", sigma3/sigma1 = " + Fmt(sv(2) / s1) + " < coplanar_ratio_min = " +
                      Fmt(options.coplanar_ratio_min) +
                      "; teach P4 far from the plane of P1..P3 (paper section 3)";
      return result;
    }
  }

  // Advice against the paper's recommended triangular pyramid with ~1 m sides (section 3).
  double diameter = 0.0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) diameter = std::max(diameter, (p_B2[i] - p_B2[j]).norm());
  if (diameter < options.side_warn_fraction * options.recommended_side_m) {
    result.warnings.push_back("contacts span only " + Fmt(diameter) +
                              " m; the paper recommends a triangular pyramid with sides of about " +
                              Fmt(options.recommended_side_m) + " m or more");
  }
  if (sv2(2) / sv2(0) < options.flatness_warn_ratio) {
    result.warnings.push_back("contacts are far from a triangular pyramid: singular values " +
                              SingularValuesText(sv2) + ", sigma3/sigma1 = " +
                              Fmt(sv2(2) / sv2(0)) + " < flatness_warn_ratio = " +
                              Fmt(options.flatness_warn_ratio) +
                              "; teach P4 further from the plane of P1..P3");
  }

  // General linear solution (ref. [8], paper section 2.2): least squares for [R | t] in
  // p_B1 = R p_B2 + t; centring separates t, and the normal equations of Q2 R^T = Q1 give R
  // (exact for N = 4; well conditioned, since sigma3/sigma1 >= coplanar_ratio_min here).
  const Matrix3 normal = Q2.transpose() * Q2;
  const Matrix3 R_prelim = normal.ldlt().solve(Q2.transpose() * Q1).transpose();  // eq. 7
  const Matrix3 R_general = NearestRotation(R_prelim);                      // eq. 3
  result.X_B1B2_general = WithTranslation(R_general, mean_B1, mean_B2);     // eq. 12
  result.rms_residual_general_m = RmsResidual(p_B1, p_B2, result.X_B1B2_general);

  RefinedRotation refined;
  switch (constraint) {
    case BaseConstraint::kFloorFloor: refined = FloorFloor(R_prelim); break;
    case BaseConstraint::kFloorCeiling: refined = FloorCeiling(R_prelim); break;
    case BaseConstraint::kFloorWall: refined = FloorWall(R_prelim, R_general, options); break;
    case BaseConstraint::kGeneral:
      refined.ok = true;
      refined.R = R_general;
      break;
  }
  result.X_B1B2_constrained = WithTranslation(refined.R, mean_B1, mean_B2);  // eq. 12
  result.rms_residual_constrained_m = RmsResidual(p_B1, p_B2, result.X_B1B2_constrained);
  if (!refined.ok) {
    result.status = constraint == BaseConstraint::kFloorWall ? Status::kNotConverged
                                                             : Status::kDegenerate;
    result.reason = refined.reason;
    return result;
  }

  const double mismatch = RotationAngle(R_general, refined.R);
  if (mismatch > options.installation_mismatch_warn_rad) {
    result.warnings.push_back(std::string("the ") + ToString(constraint) +
                              " rotation differs from the general one by " +
                              Fmt(RadToDeg(mismatch)) + " deg (> installation_mismatch_warn_rad = " +
                              Fmt(RadToDeg(options.installation_mismatch_warn_rad)) +
                              " deg): check the declared installation");
  }
  result.status = Status::kSuccess;
  return result;
}

}  // namespace twin
