// Full nonlinear least-squares identification from optical-axis samples (Zhu et al. 2019,
// section III.B, eq. 13-15), solved by the identification engine (engine.h) with one
// OpticalAxisSet: the alternative to the paper's linearized, recursive method
// (linearized_identification.h), against which it is tested.
//
// Unknowns: the kinematic correction in the identifiable subspace (the engine's SVD of the
// profiled, weighted Jacobian; LineConstraintInvariants are named unidentifiable), so the
// unidentifiable combinations keep exactly zero correction; and one nuisance line per optical
// axis (optical_axis_residual.h, initialised by FitLine on the nominal positions).
//
// Beyond the paper: the scale measurement. The collinearity constraint cannot see a uniform
// scale of the arm (lines stay lines). When the samples carry depths z_i (distance of P from
// the camera along the axis, from the board pose and the known square length), each adds one
// residual: the position of P along the line must follow the measured depth up to one unknown
// offset t_k per axis. The scale of the arm then enters the data, and the uniform-scale
// direction leaves the unidentifiable set; rotation about and translation along base z
// (link1.theta, link1.d) stay unidentifiable.
#pragma once

#include <string>
#include <vector>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/identification/engine.h"
#include "calib/identification/linearized_identification.h"
#include "calib/identification/observability.h"
#include "calib/measurements/optical_axis_model.h"
#include "calib/model/parameters.h"

namespace twin {

/// Robust loss on each sample's residual block.
enum class NonlinearLoss {
  kNone,   ///< plain squared distance
  kHuber,  ///< ceres::HuberLoss with scale huber_scale [m]
};

/// Options of IdentifyNonlinear; defaults suit the paper's 5 axes x 10 positions.
struct NonlinearIdentificationOptions {
  int max_iterations = 200;            ///< Ceres max_num_iterations (>= 1)
  double function_tolerance = 1e-14;   ///< Ceres relative cost-change tolerance, in (0, 1)
  double gradient_tolerance = 1e-16;   ///< Ceres gradient tolerance, > 0
  double parameter_tolerance = 1e-14;  ///< Ceres relative step tolerance, > 0
  double rank_tolerance = 1e-6;        ///< relative singular-value cut of AnalyseObservability
  NonlinearLoss loss = NonlinearLoss::kNone;  ///< robust loss per sample
  double huber_scale = 1e-4;           ///< Huber threshold on the distance [m] (> 0), if kHuber
  /// Use the samples' measured depths (AxisSample::depth) when every sample has one: the
  /// scale measurement that makes the uniform scale of the arm identifiable (see above).
  bool use_depth = true;
  /// Weight of a depth residual relative to a perpendicular one, sigma_perpendicular /
  /// sigma_depth [-]; 0 estimates it from the data (variance components, two solves).
  double depth_weight = 0.0;
  /// Solves again from the solution, the identifiable subspace taken there, at most this
  /// many times (>= 0). The nominal model's subspace is a linearization at a point of
  /// symmetry (exactly parallel and perpendicular axes): some directions null there are not
  /// null at the real arm, and with errors of a few millimetres and half a degree the fit
  /// without them stops short of the data (twin, twice Table 3's errors, trial 2's r1: RMS
  /// distance 0.023 mm at rank 19, 0.0073 mm at rank 21 from the first solution). A pass is
  /// kept when the RMS distance drops by more than 1 % at the same rank, or, when the rank
  /// rose, when the drop in the sum of squares is significant at 0.1 % (chi-square with the
  /// added directions' count); a rank that falls stops.
  int relinearize_passes = 3;
  /// Weight each sample by its own sigmas (AxisSample::sigma_offset, sigma_depth: the board
  /// pose's covariance) within its group; the groups' weights are still estimated (or given
  /// by depth_weight). A board's depth noise grows with its distance, so uniform weights let
  /// the far samples set the scale. false: every sample of a group alike.
  bool use_sample_sigmas = true;
};

/// Throws PreconditionError naming the bad field and value (no user input sets these options).
void ValidateNonlinearIdentificationOptions(const NonlinearIdentificationOptions& options);

enum class NonlinearIdentificationStatus {
  kConverged,      ///< Ceres reported CONVERGENCE
  kMaxIterations,  ///< Ceres stopped at max_iterations (NO_CONVERGENCE); the model is usable
  kFailed,         ///< Ceres reported FAILURE or USER_FAILURE; the model is the nominal one
};

/// Name of a status for messages ("converged", "max_iterations", "failed").
const char* ToString(NonlinearIdentificationStatus status);

/// Outcome of IdentifyNonlinear.
struct NonlinearIdentificationResult {
  NonlinearIdentificationStatus status = NonlinearIdentificationStatus::kFailed;
  std::string reason;                 ///< why it stopped (Ceres' message)
  std::string brief_report;           ///< ceres::Solver::Summary::BriefReport()
  int iterations = 0;                 ///< Ceres iterations (successful and not)
  KinematicModel model;               ///< nominal + correction
  ParameterVector correction;         ///< identified - nominal [m, rad]
  /// Coordinates of the last kept pass's step in observability.identifiable_basis (from that
  /// pass's start, which is the nominal model only when passes == 1).
  Eigen::VectorXd z;
  std::vector<Line3> axes;            ///< the fitted optical axes in B (unit directions)
  double rms_distance_before = 0.0;   ///< RMS point-to-line distance, nominal, FitLine axes [m]
  double rms_distance_after = 0.0;    ///< RMS point-to-line distance at the solution [m]
  bool depth_used = false;            ///< depth residuals entered the problem
  double depth_weight = 0.0;          ///< weight used (given or estimated) [-]
  double rms_depth_residual = 0.0;    ///< RMS of (along-line position - t_k - z_i) [m]
  /// Length ratio identified / nominal along the uniform-scale direction: 1 + (projection
  /// of the correction onto the scale direction) [-]; exactly 1 without depth.
  double scale = 1.0;
  /// Identifiability at the start of the last pass (the nominal model unless a relinearized
  /// pass was kept, see relinearize_passes); its null space got exactly zero correction in
  /// that pass.
  ObservabilityReport observability;
  int passes = 1;  ///< solves kept: 1 + the relinearized ones that lowered the RMS distance
  /// The engine's result: 1-sigma of every parameter, correlations, residual variance.
  IdentificationResult engine;
};

/// Identifies the passive robot's 35 link parameters by minimizing the sum of squared
/// point-to-line distances (eq. 13-15) over the correction z and the 5-DOF axis lines. Axis
/// indices must be 0..q-1 with >= 3 samples each (throws InputError otherwise).
NonlinearIdentificationResult IdentifyNonlinear(
    const KinematicModel& nominal, const std::vector<AxisSample>& samples,
    const NonlinearIdentificationOptions& options = {});

/// The identifiability of IdentifyNonlinear's problem at `nominal` without solving it: the
/// observability report of its first pass (the same measurement set, initial weights and
/// nuisance lines fitted to the nominal positions, the same rank tolerance), from one Jacobian.
/// Same input checks as IdentifyNonlinear.
ObservabilityReport NonlinearIdentifiability(const KinematicModel& nominal,
                                             const std::vector<AxisSample>& samples,
                                             const NonlinearIdentificationOptions& options = {});

/// Perpendicular residual (3 rows [m]) of one sample, evaluated in double through the same
/// residual functor the solver differentiates (OpticalAxisResidual); `phi` the geometric
/// parameters, `point` and unit `direction` the line. Exposed for tests.
Vector3 AxisResidual(const KinematicModel& model_without_params, const ParameterVector& phi,
                     const JointVector& q, const Vector3& point, const Vector3& direction);

}  // namespace twin
