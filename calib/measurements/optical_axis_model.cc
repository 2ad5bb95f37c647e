#include "calib/measurements/optical_axis_model.h"

#include <string>

#include <Eigen/Eigenvalues>

#include "calib/common/errors.h"

namespace twin {
namespace {

// Orients `dir` from the first point towards the last one.
Vector3 Oriented(Vector3 dir, const std::vector<Vector3>& points) {
  if (dir.dot(points.back() - points.front()) < 0.0) dir = -dir;
  return dir;
}

// Two unit vectors spanning the plane perpendicular to unit mu.
Eigen::Matrix<double, 3, 2> TangentBasis(const Vector3& mu) {
  const Vector3 helper = std::abs(mu.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = mu.cross(helper).normalized();
  B.col(1) = mu.cross(B.col(0));
  return B;
}

}  // namespace

Line3 FitLine(const std::vector<Vector3>& points) {
  if (points.size() < 2) {
    throw InputError("FitLine", "needs at least 2 points, got " + std::to_string(points.size()));
  }
  Vector3 centroid = Vector3::Zero();
  for (const Vector3& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  // Principal direction of the scatter matrix (equivalent to the SVD of the centred points).
  Matrix3 scatter = Matrix3::Zero();
  for (const Vector3& p : points) scatter += (p - centroid) * (p - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Matrix3> eig(scatter);
  if (!(eig.eigenvalues()(2) > 0.0)) {
    throw InputError("FitLine", "all points coincide; no direction");
  }
  return {centroid, Oriented(eig.eigenvectors().col(2).normalized(), points)};
}

Line3 FitLineEq45(const std::vector<Vector3>& points) {
  if (points.size() < 2) {
    throw InputError("FitLineEq45",
                     "needs at least 2 points, got " + std::to_string(points.size()));
  }
  // Eq. 45: [m x0; n y0] = [sum xz, sum x; sum yz, sum y] [sum z^2, sum z; sum z, p]^-1.
  Eigen::Matrix<double, 2, 2> lhs = Eigen::Matrix2d::Zero(), N = Eigen::Matrix2d::Zero();
  for (const Vector3& p : points) {
    lhs(0, 0) += p.x() * p.z();
    lhs(0, 1) += p.x();
    lhs(1, 0) += p.y() * p.z();
    lhs(1, 1) += p.y();
    N(0, 0) += p.z() * p.z();
    N(0, 1) += p.z();
    N(1, 1) += 1.0;
  }
  N(1, 0) = N(0, 1);
  const double det = N.determinant();
  // det = p * sum (z - mean z)^2: zero when the axis is perpendicular to base z.
  if (!(std::abs(det) > 1e-12 * N(1, 1) * N(1, 1))) {
    throw InputError("FitLineEq45",
                     "z coordinates do not vary (axis perpendicular to base z); use FitLine");
  }
  const Eigen::Matrix2d mx = lhs * N.inverse();
  const Vector3 mu = Vector3(mx(0, 0), mx(1, 0), 1.0).normalized();
  return {Vector3(mx(0, 1), mx(1, 1), 0.0), Oriented(mu, points)};
}

Vector3 MisalignedError(const Vector3& mu, const Vector3& p_i, const Vector3& p_j) {
  return mu.cross(p_j - p_i);  // eq. 18/46
}

Eigen::Matrix<double, 3, Eigen::Dynamic> ErrorJacobian(const KinematicModel& model, const Vector3& mu,
                                                   const JointVector& q_i,
                                                   const JointVector& q_j) {
  // Eq. 19; IdentificationJacobian rows 0-2 are already 0R_N J_P (base frame, eq. 12).
  const Eigen::Matrix<double, 3, Eigen::Dynamic> Ji = IdentificationJacobian(model, q_i).topRows<3>();
  const Eigen::Matrix<double, 3, Eigen::Dynamic> Jj = IdentificationJacobian(model, q_j).topRows<3>();
  return SkewMatrix(mu) * (Ji - Jj);
}

int ValidateAxisSamples(const std::vector<AxisSample>& samples) {
  std::vector<int> count;
  for (size_t n = 0; n < samples.size(); ++n) {
    const AxisSample& s = samples[n];
    const std::string where = "samples[" + std::to_string(n) + "]";
    if (s.axis < 0) throw InputError(where + ".axis", "negative: " + std::to_string(s.axis));
    if (!s.q.allFinite()) throw InputError(where + ".q", "not finite");
    if (!s.offset.allFinite()) throw InputError(where + ".offset", "not finite");
    if (static_cast<int>(count.size()) <= s.axis) count.resize(s.axis + 1, 0);
    ++count[s.axis];
  }
  if (count.empty()) throw InputError("samples", "empty");
  for (size_t k = 0; k < count.size(); ++k) {
    if (count[k] < 3) {
      throw InputError("samples", "axis " + std::to_string(k) + " has " +
                                      std::to_string(count[k]) +
                                      " samples; each axis 0..q-1 needs >= 3");
    }
  }
  return static_cast<int>(count.size());
}

std::vector<std::vector<Vector3>> AxisPoints(const KinematicModel& model,
                                             const std::vector<AxisSample>& samples) {
  std::vector<std::vector<Vector3>> pts;
  for (const AxisSample& s : samples) {
    if (s.axis < 0) throw InputError("AxisSample.axis", "negative: " + std::to_string(s.axis));
    if (static_cast<int>(pts.size()) <= s.axis) pts.resize(s.axis + 1);
    pts[s.axis].push_back(AxisPoint(model, s));
  }
  return pts;
}

std::vector<Line3> FitAxes(const KinematicModel& model, const std::vector<AxisSample>& samples) {
  std::vector<Line3> lines;
  for (const auto& pts : AxisPoints(model, samples)) lines.push_back(FitLine(pts));
  return lines;
}

Vector3 AxisPoint(const KinematicModel& model, const AxisSample& sample) {
  return EndPose(model, sample.q).translation() - sample.offset;
}

MisalignedErrorStack StackMisalignedErrors(const KinematicModel& model,
                                           const std::vector<AxisSample>& samples,
                                           const std::vector<Vector3>& directions) {
  const int num_axes = static_cast<int>(directions.size());
  // Per axis: positions and position Jacobians of its samples, in sample order.
  std::vector<std::vector<Vector3>> p(num_axes);
  std::vector<std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>>> J(num_axes);
  for (const AxisSample& s : samples) {
    // The directions are fitted to (or planned for) these same samples by the caller.
    TWIN_REQUIRE(s.axis >= 0 && s.axis < num_axes,
                 "sample of axis " + std::to_string(s.axis) + " has no direction (" +
                     std::to_string(num_axes) + " given)");
    const FrameSet frames = ForwardKinematics(model, s.q);
    p[s.axis].push_back(frames.X_BE.translation() - s.offset);
    J[s.axis].push_back(IdentificationJacobian(model, s.q).topRows<3>());
  }
  MisalignedErrorStack out;
  for (int k = 0; k < num_axes; ++k) {
    const int n = static_cast<int>(p[k].size());
    TWIN_REQUIRE(n >= 2, "axis " + std::to_string(k) + " has " + std::to_string(n) +
                             " samples, needs >= 2 (the caller's samples were validated)");
    out.num_pairs += n * (n - 1) / 2;
  }
  const int rows = 3 * out.num_pairs;
  out.E.resize(rows);
  out.Phi.resize(rows, model.num_parameters());
  out.direction_jacobian = Eigen::MatrixXd::Zero(rows, 2 * num_axes);
  int r = 0;
  for (int k = 0; k < num_axes; ++k) {
    out.axis_row_begin.push_back(r);
    const Vector3 mu = directions[k].normalized();
    const Matrix3 S = SkewMatrix(mu);
    const Eigen::Matrix<double, 3, 2> T = TangentBasis(mu);
    const int n = static_cast<int>(p[k].size());
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j, r += 3) {
        const Vector3 dp = p[k][j] - p[k][i];
        out.E.segment<3>(r) = MisalignedError(mu, p[k][i], p[k][j]);    // eq. 46
        out.Phi.middleRows<3>(r) = S * (J[k][i] - J[k][j]);  // eq. 19
        // d(mu x dp)/d(mu) = -[dp x], restricted to the tangent plane of mu.
        out.direction_jacobian.block<3, 2>(r, 2 * k) = -SkewMatrix(dp) * T;
      }
    }
  }
  out.axis_row_begin.push_back(r);
  return out;
}

Eigen::MatrixXd ProfiledPhi(const MisalignedErrorStack& stack) {
  // A is block diagonal (one 2-column block per axis), so project axis by axis; each block's
  // range gets an orthonormal basis by Gram-Schmidt (a column of a degenerate axis is skipped).
  Eigen::MatrixXd out = stack.Phi;
  const Eigen::MatrixXd& A = stack.direction_jacobian;
  for (int k = 0; k + 1 < static_cast<int>(stack.axis_row_begin.size()); ++k) {
    const int c = 2 * k, r0 = stack.axis_row_begin[k], r1 = stack.axis_row_begin[k + 1];
    if (r1 == r0) continue;
    const Eigen::MatrixXd block = A.block(r0, c, r1 - r0, 2);
    auto rows = out.middleRows(r0, r1 - r0);
    const double scale = block.norm();
    std::vector<Eigen::VectorXd> basis;
    for (int j = 0; j < 2; ++j) {
      Eigen::VectorXd u = block.col(j);
      for (const auto& b : basis) u -= b * b.dot(u);
      if (u.norm() > 1e-12 * scale) basis.push_back(u.normalized());
    }
    for (const auto& b : basis) rows -= b * (b.transpose() * rows);
  }
  return out;
}

double MeanMisalignedErrorNorm(const KinematicModel& model,
                               const std::vector<AxisSample>& samples) {
  double sum = 0.0;
  int count = 0;
  for (const auto& pts : AxisPoints(model, samples)) {
    if (pts.empty()) continue;
    const Vector3 mu = FitLine(pts).direction;
    for (size_t i = 0; i < pts.size(); ++i) {
      for (size_t j = i + 1; j < pts.size(); ++j, ++count) {
        sum += MisalignedError(mu, pts[i], pts[j]).norm();
      }
    }
  }
  return count > 0 ? sum / count : 0.0;
}

}  // namespace twin
