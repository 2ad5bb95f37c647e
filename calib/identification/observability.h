// Identifiability of the kinematic parameters from an error model E = Phi dphi (Zhu et al. 2019,
// eq. 21), and the observability index O1 (eq. 34). DESIGN.md convention 8: combinations of
// parameters that the data cannot see are named and reported, not regularized away.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/model/parameters.h"

namespace twin {


/// Result of AnalyseObservability. All bases are in scaled parameter coordinates x, where a
/// physical correction is dphi = column_scale.asDiagonal() * x (SI units: m, rad, ...).
struct ObservabilityReport {
  int rank = 0;                              ///< number of identifiable directions
  std::vector<double> singular_values;       ///< of the column-scaled matrix, descending
  /// One named combination per unidentifiable direction, e.g. "r2.link1.theta" or
  /// "0.707 r2.link2.d - 0.707 r2.link3.d" (SI coefficients of a unit vector; the basis is the
  /// reduced row echelon form of the null-space basis, coefficients below 1e-6 dropped).
  std::vector<std::string> unidentifiable;
  Eigen::MatrixXd identifiable_basis;        ///< n x rank, orthonormal columns
  Eigen::MatrixXd null_basis;                ///< n x (n - rank), orthonormal columns
  Eigen::VectorXd column_scale;              ///< scaled -> SI factor per column (n)
  /// sigma_max / sigma_min over the identifiable singular values (1 for rank 1, infinity for
  /// rank 0) [-].
  double condition_number() const;
};

/// SVD of Phi (rows x n) after multiplying column j by column_scale(j) (the SI size of one
/// scaled unit of parameter j, so that the columns weigh alike); rank = number of singular
/// values above relative_tolerance * sigma_max. `known_invariants` are parameter directions
/// (SI) known from theory to be unobservable (for example a uniform scale of all lengths for
/// line constraints): the null space is then the span of Phi's numerical null space and these
/// directions, so they land in it even where noisy or inconsistent data give them a small
/// non-zero singular value; singular_values are then those of Phi restricted to the complement.
/// `names` (n) name the columns. Throws PreconditionError for mismatched sizes or a tolerance
/// outside (0, 1).
ObservabilityReport AnalyseObservability(const Eigen::MatrixXd& Phi,
                                         const std::vector<std::string>& names,
                                         const Eigen::VectorXd& column_scale,
                                         double relative_tolerance,
                                         const std::vector<Eigen::VectorXd>& known_invariants = {});

/// The same for the geometric parameters of `model` (columns in parameters.h order, length
/// columns scaled by kObservabilityCharacteristicLength, angles by 1).
ObservabilityReport AnalyseObservability(const Eigen::MatrixXd& Phi, const KinematicModel& model,
                                         double relative_tolerance,
                                         const std::vector<Eigen::VectorXd>& known_invariants = {});

/// The first part of AnalyseObservability alone, with the same arithmetic: the singular values
/// (descending) and the rank, without the bases and the names of the unidentifiable
/// combinations (what the pose planner's fitness needs, many thousand times). Same
/// requirements and errors.
struct SingularValuesAndRank {
  std::vector<double> singular_values;
  int rank = 0;
};
SingularValuesAndRank ObservabilitySingularValues(
    const Eigen::MatrixXd& Phi, const Eigen::VectorXd& column_scale, double relative_tolerance,
    const std::vector<Eigen::VectorXd>& known_invariants = {});

/// Column scales of the geometric parameters of `model` (see above).
Eigen::VectorXd GeometricColumnScale(const KinematicModel& model);

/// Observability index O1 of eq. 34: (sigma_1 ... sigma_m)^(1/m) / sqrt(m), m the number of
/// values given. Pass the identifiable singular values only (the first `rank` of a report): an
/// unidentifiable direction has sigma = 0 and would zero the product whatever the poses, so O1
/// could no longer rank pose sets. Computed through logarithms (no overflow). Returns 0 for an
/// empty list or any non-positive value.
double ObservabilityIndexO1(const std::vector<double>& identifiable_singular_values);

/// Orthonormal basis (columns) of the span of A's columns: a rank-revealing QR with a relative
/// threshold of 1e-10 of the largest pivot. With `unit_columns`, each column is scaled to unit
/// length first, so that the cut does not depend on the columns' units (zero columns add
/// nothing). A with no columns gives a basis with no columns.
Eigen::MatrixXd SpanBasis(const Eigen::MatrixXd& A, bool unit_columns = false);

/// Readable name of an SI parameter direction (unit-normalized, |coefficients| < 1e-6
/// dropped), e.g. "0.707 r2.link2.d - 0.707 r2.link3.d"; a single term is just its name.
std::string NameCombination(const Eigen::VectorXd& direction,
                            const std::vector<std::string>& names);

}  // namespace twin
