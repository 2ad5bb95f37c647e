// A store of finished pose plans, so that runs whose planner inputs are equal plan once (the
// trials of a Monte Carlo study that differ only in the truth share one plan). The plan of
// PlanCalibrationPoses depends only on what the estimator is told: the nominal models, the
// rough base-to-base and hand-eye transforms and the planner options (seed included, threads
// not). calib/ defines the inputs and the interface; where plans are kept is the caller's
// (bench/runs/plan_cache.h keeps them as files).
#pragma once

#include <optional>
#include <string>

#include "calib/kinematics/kinematic_model.h"
#include "calib/planning/pose_planner.h"

namespace twin {

/// Everything PlanCalibrationPoses' result depends on.
struct PlanInputs {
  KinematicModel active;                   ///< nominal model of the camera robot
  KinematicModel passive;                  ///< nominal board-robot model (board as link 7)
  Transform X_BaBp = Transform::Identity();  ///< rough passive base in the active base
  Transform X_FC = Transform::Identity();    ///< rough hand-eye
  PosePlannerOptions options;              ///< the planner's options
};

/// Canonical text of the inputs: every number that can change the plan, written exactly (C99
/// hexadecimal floats), one `key value` per line; options.threads is left out (the plan does
/// not depend on it). Equal texts mean equal plans.
std::string PlanInputsText(const PlanInputs& inputs);

/// Where plans are looked up before planning and kept after.
class PlanStore {
 public:
  virtual ~PlanStore() = default;
  /// The plan stored for `inputs`, or nullopt. A store shared by processes may make a caller
  /// that gets nullopt the one that plans (others wait in Find until Store or Abandon).
  virtual std::optional<PosePlanResult> Find(const PlanInputs& inputs) = 0;
  /// Keeps a successful plan for `inputs` (after a Find that returned nullopt).
  virtual void Store(const PlanInputs& inputs, const PosePlanResult& plan) = 0;
  /// The caller that got nullopt from Find will not Store (planning failed).
  virtual void Abandon(const PlanInputs& inputs) = 0;
};

}  // namespace twin
