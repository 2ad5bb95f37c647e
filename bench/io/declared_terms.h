// What the estimator is told of the twin's effects: a scenario effect with `declared: true`
// says that the effect exists (its term type and joint), never its magnitude
// (docs/explanation/discovery-statistics.md). Shared by the tracker and the optical-axis runs.
#pragma once

#include <string>
#include <vector>

#include "bench/io/scenario.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/model/robot_model.h"

namespace twin {

/// Where a declared warm-up's time constant starts [min] (the twin's thermal_drift declared:
/// the estimator's thermal_warmup, its time constant then estimated; one of model discovery's
/// warm-up starts, 10 / 20 / 40 / 80 min).
inline constexpr int kDeclaredWarmupStartMin = 20;

/// The estimator's starting model for robot `robot` (0-based): `nominal` plus a term, at zero,
/// for every declared effect of the scenario on that robot that the estimator's library has,
/// by type and joint only. Declared effects without a term (geometry errors, noise) need none;
/// one the procedure cannot model (a thermal growth without temperatures) is said in `notes`.
RobotModel DeclaredModel(const Scenario& sc, int robot, const KinematicModel& nominal,
                         std::vector<std::string>* notes);

}  // namespace twin
