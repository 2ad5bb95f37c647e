// Typed results of a handclasp base-frame calibration stage on the twin
// (bench/runs/handclasp_run.h): what the procedure estimated and how the bench scored it against
// the twin's truth. bench/report/handclasp_report.h writes them as report.json; the dual-arm
// workflow and the console summaries read them directly.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "calib/identification/base_calibration.h"
#include "calib/procedures/handclasp_procedure.h"

namespace twin {

/// One X_B1B2 estimate scored (eq. 33-34) against the frames the kinematic models use
/// (KinematicFrameTruth) and against the physical X_B1B2.
struct ScoredBaseFrame {
  bool present = false;  ///< the estimate exists (its procedure step succeeded)
  BaseFrameError kinematic;
  BaseFrameError physical;
};

/// How a handclasp stage ended.
enum class HandclaspStageStatus {
  kOk,               ///< the procedure calibrated; estimates scored
  kTeachingFailed,   ///< too few teachable points; nothing measured
  kProcedureFailed,  ///< the contacts or the calibration failed (HandclaspResult::reason)
};

/// The points the operator taught, as planned or listed.
struct HandclaspTeaching {
  BaseConstraint installation = BaseConstraint::kGeneral;  ///< the constraint used
  double operator_error_m = 0.0;   ///< the simulated operator's alignment error sigma [m]
  bool planned = true;             ///< points planned (auto) rather than listed
  int orientations_per_point = 1;  ///< taught tip orientations per point
  TaughtPoints taught;             ///< the planner's outcome
};

/// A truth-only diagnostic: a pendant tip model against the true tip in the scoring frame.
struct PendantTipError {
  double rms_mm = 0.0, max_mm = 0.0;
  int configurations = 0;  ///< seeded random joint configurations compared
};

/// The frames the estimates were scored in (bench only, after the procedure).
struct HandclaspScoringFrames {
  bool best_fit = false;  ///< best-fit frames (calibrated models), else link-1 frames
  Transform truth = Transform::Identity();     ///< X_B1'B2', what estimates are scored against
  Transform physical = Transform::Identity();  ///< the physical X_B1B2
  std::array<Transform, 2> X_BBp = {Transform::Identity(), Transform::Identity()};  ///< B' in B
  /// Link-1 frames: true minus pendant link-1 theta [rad] and d [m], per robot.
  std::array<double, 2> dtheta1_rad = {0.0, 0.0}, dd1_m = {0.0, 0.0};
  std::array<PendantTipError, 2> pendant_tip_error;
};

/// The coupled-motion check: robot 2 follows robot 1's tip through the delivered estimate.
struct CoupledMotionResult {
  bool ok = false;
  std::string reason;                ///< why not ok
  std::string estimate;              ///< "tips_identified" or "constrained"
  std::string skipped;               ///< why it did not run (a cell without truth); ok false
  std::vector<double> deviation_mm;  ///< true tip-to-tip distance after each step [mm]
  double max_deviation_mm = 0.0;     ///< NaN when not measured
};

/// Estimates of one handclasp stage, typed, with the bench's scores.
struct HandclaspStageResult {
  HandclaspStageStatus status = HandclaspStageStatus::kTeachingFailed;
  /// Why not ok: with kTeachingFailed "teaching: " and the planner's reason, with
  /// kProcedureFailed the procedure's reason; empty when ok.
  std::string reason;
  HandclaspTeaching teaching;
  /// False on a cell without truth (a real cell): the estimates alone, their errors NaN, no
  /// scoring frames; the coupled-motion check skipped (coupled_motion->skipped says why).
  bool truth_available = true;
  HandclaspScoringFrames frames;  ///< unless kTeachingFailed or without truth
  HandclaspResult procedure;      ///< contacts, skipped, calibration, tips (unless teaching failed)
  bool tips_attempted = false;    ///< the stage asked for the tips (HandclaspStageOptions)
  ScoredBaseFrame general, constrained;  ///< eq. 3 and 12; the refined one
  ScoredBaseFrame tips;                  ///< jointly with the tips, if identified
  std::optional<CoupledMotionResult> coupled_motion;  ///< when the check ran
  std::optional<std::uint64_t> seed;                  ///< the twin's seed of a batch trial
  /// Largest tip-to-tip deviation of the coupled-motion check [mm]; NaN when not run or failed.
  double coupled_motion_max_deviation_mm = std::numeric_limits<double>::quiet_NaN();

  bool ok() const { return status == HandclaspStageStatus::kOk; }
  /// The estimate the stage delivers: with the tips when identified, else the constrained one.
  const ScoredBaseFrame& delivered() const { return tips.present ? tips : constrained; }
  const char* delivered_name() const { return tips.present ? "tips_identified" : "constrained"; }
  Transform X_B1B2_general = Transform::Identity();      ///< general estimate (eq. 3, 12)
  Transform X_B1B2_constrained = Transform::Identity();  ///< installation-refined estimate
  /// With HandclaspStageOptions::identify_tips and the tips identified: the estimate refined
  /// jointly with the tips.
  Transform X_B1B2_tips = Transform::Identity();
};

/// A seeded batch of handclasp trials (trial t on a twin with seed scenario seed + t).
struct HandclaspBatchResult {
  int trials = 1;                           ///< trials asked for
  int failures = 0;                         ///< trials whose procedure refused
  std::vector<HandclaspStageResult> done;   ///< the trials that ran, in order (trial 0 first)
};

}  // namespace twin
