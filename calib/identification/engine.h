// The identification engine (DESIGN.md, "the estimator model"): one Ceres problem from any mix
// of measurement sets (optical axes, tracker points, ...) and a robot model with error terms.
//
// 1. Observability first: the stacked, weighted Jacobian of every residual at the starting
//    point, with the nuisance parameters (lines, tracker pose) profiled out, column-scaled by
//    the layout's scales, is analysed by SVD (AnalyseObservability): the identifiable
//    combinations are its row space, the rest are named (with the sets' known invariants).
//    The geometry's unidentifiable combinations are those with every term at zero: a term
//    that acts (a start from an earlier solution) scales or bends the geometric columns a
//    little, which would make such combinations look identifiable through the term's model
//    alone (a thermal growth of 1e-4 separates a joint link's length from the tool's); they
//    are held as at the terms' zero.
// 2. The model's parameters move only in the identifiable subspace: phi = phi0 + S V z, a
//    linear manifold on the model block, so unidentifiable combinations keep their values.
//    Parameters the caller fixes are left out of the analysis and held.
// 3. Levenberg-Marquardt (Ceres), then optionally the residual groups' weights re-estimated
//    (variance components: 1 / sigma_g from each group's sum of squares and redundancy) and a
//    second solve.
// 4. Uncertainty: covariance of z and the nuisance from the Jacobian at the solution, times the
//    residual variance (sigma0^2 = 2 cost / redundancy, the independent rows less the
//    unknowns), mapped to every parameter:
//    Cov_phi = S V Cov_z V^T S; 1-sigma and the strongest correlations between parameters.
// Memory and time are linear in the number of measurements (the dense Jacobian has one row per
// residual row and one column per unknown; the SVD works on its R factor).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/identification/observability.h"
#include "calib/measurements/measurement_set.h"
#include "calib/model/parameter_layout.h"
#include "calib/model/robot_model.h"

namespace twin {

/// Options of Identify; defaults suit calibration data of tens to thousands of measurements.
struct IdentificationOptions {
  int max_iterations = 200;            ///< Ceres max_num_iterations per solve (>= 1)
  double function_tolerance = 1e-14;   ///< Ceres relative cost-change tolerance, in (0, 1)
  double gradient_tolerance = 1e-16;   ///< Ceres gradient tolerance, > 0
  double parameter_tolerance = 1e-14;  ///< Ceres relative step tolerance, > 0
  double rank_tolerance = 1e-6;        ///< relative singular-value cut of AnalyseObservability
  /// Re-estimate each residual group's weight after a first solve and solve again (variance
  /// components), for sets with several groups of unknown relative noise.
  bool estimate_group_weights = true;
  /// Parameters held at their values, by full name ("r1.link7.alpha") or block name
  /// ("geometry", "joint_compliance (joint 2)").
  std::vector<std::string> fixed;
  int num_threads = 1;                 ///< Ceres threads (>= 1)
  /// Fill IdentificationResult::term_dependence (one more Jacobian and two QRs at the
  /// solution) for a model with terms.
  bool term_dependence = true;
  /// Report correlations with |rho| at least this [-], strongest first.
  double correlation_threshold = 0.9;
  int max_correlations = 20;           ///< at most this many correlations reported
};

/// Throws PreconditionError naming the bad field and value (no user input sets these options).
void ValidateIdentificationOptions(const IdentificationOptions& options);

enum class IdentificationStatus {
  kConverged,      ///< Ceres reported CONVERGENCE
  kMaxIterations,  ///< Ceres stopped at max_iterations; the model is usable
  kFailed,         ///< no usable solution (rank 0, or Ceres failure); the model is the start
};

/// Name of a status ("converged", "max_iterations", "failed").
const char* ToString(IdentificationStatus status);

/// How far one error term's effect on the measurements can be told from the geometry's, at the
/// solution: the canonical correlations between the span of the term's Jacobian columns and the
/// span of the free geometric columns (weighted rows, nuisance profiled out). They depend only
/// on the two spans, not on how either side is parameterized or scaled; correlations taken from
/// the covariance do, for parameters inside unidentifiable combinations (their covariance is
/// that of the identifiable projection, which follows the column scaling).
struct TermGeometryDependence {
  std::string block;  ///< the term's block name (ParameterInfo::block)
  /// One per independent direction of the term's columns (a zero column adds none),
  /// descending; 1: that direction of the term moves the measurements exactly as some
  /// geometric correction does [-]
  std::vector<double> canonical_correlations;
  /// Per direction, the free geometric parameter whose column is most aligned with it.
  std::vector<std::string> nearest_geometric;
  /// What the measurements see of the term once every other free parameter is refitted
  /// (weighted rows, nuisance profiled out): with J_T the term's columns, K the other free
  /// parameters' columns (scaled by ParameterInfo::scale) and P the projection onto the
  /// complement of K's span, visible_information = (P J_T)' (P J_T) (the term's parameters,
  /// in their flat order: an effect theta moves the weighted residuals by theta' V theta in
  /// squared norm, the non-centrality of a test for it [SI^-2]), and compensation = K^+ J_T
  /// (rows: `others`, SI), the other parameters' least-squares change that mimics theta (they
  /// move by -compensation theta when the term is left out). A direction of the others that
  /// the data barely see can take up much of a term at a large compensation: the term's
  /// detection limit is then large, as it should be.
  Eigen::MatrixXd visible_information;
  Eigen::MatrixXd compensation;
  std::vector<int> others;  ///< the flat indices of compensation's rows
  /// Largest diagonal of J_T' J_T: the scale against which visible_information's eigenvalues
  /// count as zero [SI^-2].
  double raw_information_scale = 0;
};

/// One parameter of the identified model.
struct IdentifiedParameter {
  std::string name;
  std::string unit;
  std::string block;
  double start = 0;      ///< value before identification [SI]
  double estimated = 0;  ///< value after [SI]
  /// 1-sigma [SI] with the unidentifiable combinations held (0 for a parameter that only
  /// enters unidentifiable combinations or is fixed).
  double sigma = 0;
  bool fixed = false;    ///< held by IdentificationOptions::fixed
};

/// A correlation coefficient between two parameters' estimates.
struct ParameterCorrelation {
  std::string a, b;
  double rho = 0;  ///< [-1, 1]
};

/// Per measurement set.
struct SetSummary {
  std::string kind;
  int measurements = 0;
  double rms_before = 0;  ///< RMS of ResidualNorms at the start [m]
  double rms_after = 0;   ///< ... at the solution [m]
};

/// The weight of a residual group as used in the last solve.
struct GroupSummary {
  std::string name;
  double sigma = 0;      ///< 1 / weight [m] (tracker: factor on the stated sigmas [-])
  int redundancy = 0;
};

/// Outcome of Identify.
struct IdentificationResult {
  IdentificationStatus status = IdentificationStatus::kFailed;
  std::string reason;        ///< why it stopped
  std::string brief_report;  ///< Ceres' BriefReport of the last solve
  int iterations = 0;        ///< Ceres iterations, all solves
  RobotModel model;          ///< the identified model (the start on failure)
  Eigen::VectorXd correction;  ///< estimated - start, flat [SI]
  /// Identifiability at the start (names and column scales of the free parameters; bases are
  /// over the free parameters only, see free_parameters).
  ObservabilityReport observability;
  std::vector<int> free_parameters;  ///< flat indices analysed and identified
  /// S V: the identifiable directions in SI over the full flat vector (rows: every parameter).
  Eigen::MatrixXd identifiable_directions;
  Eigen::VectorXd z;                 ///< coordinates of the correction in those directions
  std::vector<IdentifiedParameter> parameters;  ///< every parameter, flat order
  Eigen::MatrixXd covariance_z;      ///< of z (rank x rank) [-, the directions carry SI]
  Eigen::MatrixXd covariance;        ///< of the flat parameters [SI], held parameters 0
  std::vector<ParameterCorrelation> correlations;  ///< strongest first
  /// Per error term of the model (layout order), at the solution; empty without terms.
  std::vector<TermGeometryDependence> term_dependence;
  int residual_rows = 0;             ///< weighted residual rows
  int unknowns = 0;                  ///< rank + nuisance tangent dimensions
  /// Independent residual rows less all unknowns (sum of the groups' redundancies less rank).
  int redundancy = 0;
  double sigma0 = 0;                 ///< sqrt(2 cost / redundancy) [-]
  double cost_before = 0, cost_after = 0;  ///< Ceres cost (half the weighted sum of squares)
  std::vector<SetSummary> sets;
  std::vector<GroupSummary> groups;
  /// Condition number of the identifiable part (sigma_max / sigma_min) [-].
  double condition_number() const { return observability.condition_number(); }
};

/// Identifies `start` (its free parameters) from the measurement sets, which are initialised
/// here and hold the identified nuisance parameters afterwards. Throws InputError for sets
/// that do not fit the model (MeasurementSet::Validate), PreconditionError for bad options, no
/// sets or a null set.
IdentificationResult Identify(const RobotModel& start, const std::vector<MeasurementSet*>& sets,
                              const IdentificationOptions& options = {});

/// The Jacobian analysis of step 1 alone (nothing solved): identifiability of `model`'s free
/// parameters from the sets (initialised here).
ObservabilityReport AnalyseIdentifiability(const RobotModel& model,
                                           const std::vector<MeasurementSet*>& sets,
                                           const IdentificationOptions& options = {});

}  // namespace twin
