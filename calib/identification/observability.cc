#include "calib/identification/observability.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "calib/common/errors.h"

namespace twin {
namespace {

using Square = Eigen::MatrixXd;

// R factor (n x n) of a tall matrix by Givens rotations, row by row; R^T R = A^T A, so R has
// A's singular values and right singular vectors. Memory n^2 whatever the row count.
Square GivensR(const Eigen::MatrixXd& A) {
  const int n = static_cast<int>(A.cols());
  Square R = Square::Zero(n, n);
  Eigen::RowVectorXd row(n);
  for (int r = 0; r < A.rows(); ++r) {
    row = A.row(r);
    for (int j = 0; j < n; ++j) {
      if (row(j) == 0.0) continue;
      const double h = std::hypot(R(j, j), row(j));
      const double c = R(j, j) / h, s = row(j) / h;
      for (int k = j; k < n; ++k) {
        const double a = R(j, k), b = row(k);
        R(j, k) = c * a + s * b;
        row(k) = -s * a + c * b;
      }
    }
  }
  return R;
}

// Reduced row echelon form (partial pivoting on each column in order), in place.
void ReducedRowEchelon(Eigen::MatrixXd& M, double tol) {
  int lead = 0;
  for (int c = 0; c < M.cols() && lead < M.rows(); ++c) {
    Eigen::Index p;
    const double best = M.col(c).segment(lead, M.rows() - lead).cwiseAbs().maxCoeff(&p);
    if (best <= tol) continue;
    if (p != 0) M.row(lead).swap(M.row(lead + p));
    const double pivot = M(lead, c);  // copies: the row operations overwrite these entries
    M.row(lead) /= pivot;
    for (int r = 0; r < M.rows(); ++r) {
      const double f = M(r, c);
      if (r != lead) M.row(r) -= f * M.row(lead);
    }
    ++lead;
  }
}

}  // namespace

std::string NameCombination(const Eigen::VectorXd& direction,
                            const std::vector<std::string>& names) {
  const double n = direction.norm();
  if (!(n > 0.0)) return "0";
  const Eigen::VectorXd u = direction / n;
  int terms = 0, only = -1;
  for (int i = 0; i < u.size(); ++i) {
    if (std::abs(u(i)) >= 1e-6) ++terms, only = i;
  }
  if (terms == 1) return names[only];
  std::string out;
  for (int i = 0; i < u.size(); ++i) {
    if (std::abs(u(i)) < 1e-6) continue;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g ", std::abs(u(i)));
    if (out.empty()) {
      out = (u(i) < 0 ? "-" : "") + std::string(buf);
    } else {
      out += (u(i) < 0 ? " - " : " + ") + std::string(buf);
    }
    out += names[i];
  }
  return out;
}

double ObservabilityReport::condition_number() const {
  if (rank == 0) return std::numeric_limits<double>::infinity();
  return singular_values[0] / singular_values[rank - 1];
}

Eigen::VectorXd GeometricColumnScale(const KinematicModel& model) {
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(model.num_parameters());
  for (int i = 0; i < model.num_parameters(); ++i) {
    if (IsLengthParameter(i)) scale(i) = kObservabilityCharacteristicLength;
  }
  return scale;
}

ObservabilityReport AnalyseObservability(const Eigen::MatrixXd& Phi, const KinematicModel& model,
                                         double relative_tolerance,
                                         const std::vector<Eigen::VectorXd>& known_invariants) {
  return AnalyseObservability(Phi, ParameterNames(model), GeometricColumnScale(model),
                              relative_tolerance, known_invariants);
}

namespace {

// The SVD of the column-scaled Phi, with the null space widened by the known invariants (see
// the header); V only when `with_v` (the singular values do not depend on it: JacobiSVD's
// rotations are chosen from the work matrix alone).
Eigen::JacobiSVD<Square, Eigen::NoQRPreconditioner> ScaledSvd(
    const Eigen::MatrixXd& Phi, const Eigen::VectorXd& column_scale, double relative_tolerance,
    const std::vector<Eigen::VectorXd>& known_invariants, bool with_v, double* cut_out) {
  const int n = static_cast<int>(Phi.cols());
  TWIN_REQUIRE(column_scale.size() == n && n > 0,
               "Phi has " + std::to_string(Phi.cols()) + " columns and " +
                   std::to_string(column_scale.size()) + " column scales; they must agree (> 0)");
  TWIN_REQUIRE(relative_tolerance > 0.0 && relative_tolerance < 1.0,
               "relative_tolerance must be in (0, 1), got " + std::to_string(relative_tolerance));
  const Eigen::MatrixXd A = Phi * column_scale.asDiagonal();
  const Square R = GivensR(A);
  // V of the first SVD is needed for the numerical null space when there are invariants.
  Eigen::JacobiSVD<Square, Eigen::NoQRPreconditioner> svd(
      R, with_v || !known_invariants.empty() ? Eigen::ComputeFullV : 0);
  const double cut = relative_tolerance * svd.singularValues()(0);
  if (!known_invariants.empty()) {
    // Null space W = span(numerical null space of A, invariants in scaled coordinates); then
    // analyse A (I - W W^T), whose null space is exactly W. (Projecting the invariants alone
    // would break null vectors of A that overlap them.)
    std::vector<Eigen::VectorXd> w;
    auto add = [&w](Eigen::VectorXd u) {
      const double n0 = u.norm();
      for (const auto& b : w) u -= b * b.dot(u);
      for (const auto& b : w) u -= b * b.dot(u);  // second pass for orthogonality
      if (u.norm() > 1e-9 * n0) w.push_back(u.normalized());
    };
    for (int i = 0; i < n; ++i) {
      if (!(svd.singularValues()(i) > cut)) add(svd.matrixV().col(i));
    }
    for (const Eigen::VectorXd& v : known_invariants) {
      TWIN_REQUIRE(v.size() == n, "an invariant has " + std::to_string(v.size()) +
                                      " entries, expected " + std::to_string(n));
      add(v.cwiseQuotient(column_scale));
    }
    Square Q = Square::Identity(n, n);
    for (const auto& b : w) Q -= b * b.transpose();
    svd.compute(R * Q, with_v ? Eigen::ComputeFullV : 0);
  }
  *cut_out = cut;
  return svd;
}

}  // namespace

SingularValuesAndRank ObservabilitySingularValues(
    const Eigen::MatrixXd& Phi, const Eigen::VectorXd& column_scale, double relative_tolerance,
    const std::vector<Eigen::VectorXd>& known_invariants) {
  double cut = 0.0;
  const auto svd =
      ScaledSvd(Phi, column_scale, relative_tolerance, known_invariants, false, &cut);
  SingularValuesAndRank out;
  const auto& sv = svd.singularValues();
  out.singular_values.assign(sv.data(), sv.data() + sv.size());
  while (out.rank < sv.size() && sv(out.rank) > cut) ++out.rank;
  return out;
}

ObservabilityReport AnalyseObservability(const Eigen::MatrixXd& Phi,
                                         const std::vector<std::string>& names,
                                         const Eigen::VectorXd& column_scale,
                                         double relative_tolerance,
                                         const std::vector<Eigen::VectorXd>& known_invariants) {
  const int n = static_cast<int>(Phi.cols());
  TWIN_REQUIRE(static_cast<int>(names.size()) == n && column_scale.size() == n && n > 0,
               "Phi has " + std::to_string(Phi.cols()) + " columns, " +
                   std::to_string(names.size()) + " names and " +
                   std::to_string(column_scale.size()) + " column scales; they must agree (> 0)");
  ObservabilityReport rep;
  rep.column_scale = column_scale;
  double cut = 0.0;
  const auto svd = ScaledSvd(Phi, column_scale, relative_tolerance, known_invariants, true, &cut);
  const auto& sv = svd.singularValues();
  rep.singular_values.assign(sv.data(), sv.data() + sv.size());
  while (rep.rank < n && sv(rep.rank) > cut) ++rep.rank;
  rep.identifiable_basis = svd.matrixV().leftCols(rep.rank);
  rep.null_basis = svd.matrixV().rightCols(n - rep.rank);

  // Readable rotation of the null space: RREF of its basis (SI coordinates), one row each.
  Eigen::MatrixXd M = (rep.column_scale.asDiagonal() * rep.null_basis).transpose();
  // Pivot threshold 1e-4: the rows start orthonormal (entries O(0.1)), while data noise leaves
  // ~1e-7 components that must not be taken as pivots (they would be amplified).
  ReducedRowEchelon(M, 1e-4);
  for (int r = 0; r < M.rows(); ++r) {
    rep.unidentifiable.push_back(NameCombination(M.row(r).transpose(), names));
  }
  return rep;
}

double ObservabilityIndexO1(const std::vector<double>& identifiable_singular_values) {
  const int m = static_cast<int>(identifiable_singular_values.size());
  if (m == 0) return 0.0;
  double log_sum = 0.0;
  for (double s : identifiable_singular_values) {
    if (!(s > 0.0)) return 0.0;
    log_sum += std::log(s);
  }
  return std::exp(log_sum / m) / std::sqrt(static_cast<double>(m));
}

Eigen::MatrixXd SpanBasis(const Eigen::MatrixXd& A, bool unit_columns) {
  if (A.cols() == 0) return Eigen::MatrixXd(A.rows(), 0);
  Eigen::MatrixXd B = A;
  if (unit_columns) {
    for (Eigen::Index c = 0; c < B.cols(); ++c) {
      const double norm = B.col(c).norm();
      if (norm > 0.0) B.col(c) /= norm;
    }
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(B);
  qr.setThreshold(1e-10);
  return qr.householderQ() * Eigen::MatrixXd::Identity(B.rows(), qr.rank());
}

}  // namespace twin
