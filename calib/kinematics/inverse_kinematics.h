// Numeric inverse kinematics by damped least squares that respects joint limits and reports
// why it failed instead of returning a wrong answer (DESIGN.md, convention 5).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Options of SolveIk; defaults suit a 1 m industrial arm.
struct IkOptions {
  double position_tolerance = 1e-7;     ///< accepted end-frame position error [m]
  double orientation_tolerance = 1e-7;  ///< accepted end-frame orientation error [rad]
  int max_iterations = 200;             ///< damped least-squares steps per start
  double damping = 1e-3;                ///< Levenberg damping lambda of the normal equations [-]
  double max_step = 0.3;                ///< largest joint change per iteration [rad]
  double orientation_weight = 0.5;      ///< metres of error counted per radian of orientation
  bool position_only = false;           ///< ignore the orientation of the target
  int random_restarts = 24;             ///< extra starts drawn uniformly inside the limits
  std::uint64_t seed = 1;               ///< seed of the restart generator (reproducible)
};

/// Throws PreconditionError naming the bad field and value (no user input sets these options).
void ValidateIkOptions(const IkOptions& options);

enum class IkStatus {
  kSuccess,              ///< within tolerance and inside the joint limits
  kNotConverged,         ///< no start reached the tolerance (target likely unreachable)
  kJointLimits,          ///< no start converged inside the limits, one outside them did
  kInvalidInput,         ///< non-finite target or seed, or seed outside the limits
};

/// Outcome of SolveIk: q is meaningful only when status == kSuccess.
struct IkResult {
  IkStatus status = IkStatus::kNotConverged;
  std::string reason;                 ///< human-readable cause when status != kSuccess
  JointVector q;                      ///< solution (or the best attempt) [rad]
  double position_error = 0.0;        ///< |p_target - p(q)| of the returned q [m]
  double orientation_error = 0.0;     ///< angle between target and achieved rotation [rad]
  int iterations = 0;                 ///< total iterations over all starts
  int starts = 0;                     ///< starts tried (seed first, then random)
};

/// Name of a status for messages ("success", "not_converged", ...).
const char* ToString(IkStatus status);

/// Joint angles q within limits such that EndPose(model, q) equals X_BE_target (or only its
/// translation when options.position_only). Starts from q_seed, then from random starts.
IkResult SolveIk(const KinematicModel& model, const Transform& X_BE_target,
                 const JointVector& q_seed, const IkOptions& options = {});

}  // namespace twin
