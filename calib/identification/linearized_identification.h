// The recursive linearized identification of Zhu et al. 2019, section V.B (eq. 45-49): fit each
// optical axis from the current nominal positions, build E (eq. 22) and Phi (eq. 23), take a
// Levenberg-Marquardt step (eq. 48, lambda schedule eq. 49), update the model, refit the axes,
// and repeat while the calibration error eps (eq. 47) decreases.
#pragma once

#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"
#include "calib/identification/observability.h"
#include "calib/measurements/optical_axis_model.h"
#include "calib/model/parameters.h"

namespace twin {

/// Options of IdentifyFromOpticalAxes; defaults suit the paper's 5 axes x 10 positions.
struct LinearizedIdentificationOptions {
  int max_iterations = 50;             ///< accepted plus rejected LM steps, at most
  double initial_lambda = 0.01;        ///< lambda_LM(0) of eq. 48; the paper uses [0.001, 0.1]
  double lambda_factor = 5.0;          ///< h of eq. 49; the paper uses [2, 10]
  double max_lambda = 1e8;             ///< give up (eps stopped decreasing) above this lambda
  double min_relative_decrease = 1e-9; ///< an accepted step must lower eps by this fraction
  double rank_tolerance = 1e-6;        ///< relative singular-value cut of AnalyseObservability
  /// Profile the axis directions out of Phi (ProfiledPhi): the step then accounts for the
  /// refit of mu_k to first order. false uses the paper's Phi with mu_k held fixed.
  bool profile_axis_directions = true;
};

/// Throws PreconditionError naming the bad field and value (no user input sets these options).
void ValidateLinearizedIdentificationOptions(const LinearizedIdentificationOptions& options);

enum class LinearizedIdentificationStatus {
  kConverged,      ///< eps stopped decreasing (no LM step lowers it any more)
  kMaxIterations,  ///< max_iterations reached while eps was still decreasing
  kSkipped,        ///< not run (the caller's choice, e.g. too many pairs; see reason)
};

/// Name of a status for messages ("converged", "max_iterations", "skipped").
const char* ToString(LinearizedIdentificationStatus status);

/// Outcome of IdentifyFromOpticalAxes.
struct LinearizedIdentificationResult {
  LinearizedIdentificationStatus status = LinearizedIdentificationStatus::kMaxIterations;
  std::string reason;                ///< why it stopped, in words
  int iterations = 0;                ///< LM steps tried (accepted and rejected)
  KinematicModel model;              ///< the identified model (nominal + correction)
  ParameterVector correction;        ///< identified - nominal [m, rad]
  std::vector<double> eps_history;   ///< eps (eq. 47) after each accepted step, [0] = nominal [m]
  double mean_misaligned_error_before = 0.0;  ///< MeanMisalignedErrorNorm of the nominal [m]
  double mean_misaligned_error_after = 0.0;   ///< of the identified model [m]
  double final_lambda = 0.0;         ///< lambda_LM when it stopped
  /// Identifiability of the nominal model on these samples. Its null space (named in
  /// observability.unidentifiable) gets exactly zero correction.
  ObservabilityReport observability;
};

/// Parameter directions (SI) that collinearity data can never see for `model`: rotation about
/// base z (link1.theta), translation along base z (link1.d), and a uniform scale of all lengths
/// (each d and a in proportion to its current value): all three map lines to lines.
std::vector<ParameterVector> LineConstraintInvariants(const KinematicModel& model);

/// Identifies the passive robot's 35 link parameters from axis samples (section V.B). Axis
/// indices must be 0..q-1, each axis with >= 3 samples. The step of eq. 48 is solved for the
/// coordinates in observability.identifiable_basis only, so unidentifiable combinations keep
/// their nominal values. eps of eq. 47 is evaluated without linearization: the norm of E
/// recomputed at the updated model with refitted axes (the quantity eq. 47 predicts).
/// Eq. 49 as typeset divides lambda by h in both branches; here lambda / h follows a step that
/// lowers eps (accepted) and lambda * h one that does not (rejected), as in standard LM.
LinearizedIdentificationResult IdentifyFromOpticalAxes(
    const KinematicModel& nominal, const std::vector<AxisSample>& samples,
    const LinearizedIdentificationOptions& options = {});

}  // namespace twin
