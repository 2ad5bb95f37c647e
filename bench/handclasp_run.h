// The handclasp base-frame calibration of Gan, Dai, Dong 2014 run on the MuJoCo twin: parses a
// scenario's `handclasp:` section, runs calib's procedure (calib/handclasp_procedure.h) on a
// TwinCell, and scores the estimates against the twin's truth after the procedure ended
// (e_tran eq. 34, e_rot eq. 33), with a coupled-motion check (robot 2 follows robot 1 through
// the estimated base transform). Section format (all keys optional):
//
//   handclasp:
//     points: auto                 # auto (default): corners of the largest reachable cube
//                                  # between the shoulders (calib PlanTaughtPoints); or a list
//                                  # of [x, y, z] contact points in mm in robot 1's base frame
//     operator_error_mm: 0.5       # operator alignment error, sigma per axis [mm] (default 0)
//     constraint: auto             # auto (default: implied by the installations, robot 1 on
//                                  # the floor and robot 2 on floor/wall/ceiling), general,
//                                  # floor_floor, floor_wall or floor_ceiling
//     trials: 1                    # seeded batch: trial t uses seed scenario.seed + t
//     coupled_motion: true         # run the coupled-motion check (default true)
//
// Taught points are the operator's choice: the planner uses the scenario's layout of the bases
// (where the operator sees the robots stand) only to pick reachable points; the estimator gets
// contact joint readings alone.
#pragma once

#include <array>
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/scenario.h"
#include "calib/base_calibration.h"
#include "calib/kinematic_model.h"
#include "sim/twin_cell.h"

namespace twin {

/// The `handclasp:` section, in SI units.
struct HandclaspConfig {
  bool auto_points = true;             ///< plan the points (else points_B1)
  std::vector<Vector3> points_B1;      ///< contact points in B1 [m] when !auto_points
  double operator_error_m = 0.0;       ///< alignment error sigma per axis [m]
  BaseConstraint constraint = BaseConstraint::kGeneral;  ///< resolved (never "auto")
  int trials = 1;                      ///< seeded batch size (>= 1)
  bool coupled_motion = true;          ///< run the coupled-motion check
};

/// The constraint implied by the installations: robot 1 on the floor and robot 2 on the floor,
/// a wall or the ceiling give floor-floor, floor-wall, floor-ceiling; anything else general.
BaseConstraint ImpliedConstraint(const TwinSpec& twin);

/// Parses scenario.handclasp (an absent section gives the defaults). Throws InputError naming
/// "file:line scenario.handclasp.key" for unknown keys and bad values.
HandclaspConfig ParseHandclaspConfig(const Scenario& scenario);

/// Estimates of one handclasp stage and its report (bench scoring included).
struct HandclaspStageResult {
  bool ok = false;                                       ///< the procedure calibrated
  Transform X_B1B2_general = Transform::Identity();      ///< general estimate (eq. 3, 12)
  Transform X_B1B2_constrained = Transform::Identity();  ///< installation-refined estimate
  /// base_frame-style object: installation, truth, general, constrained (e_tran_mm, e_rot_deg,
  /// xyz_mm, zyz_deg, rms_residual_mm), contacts, skipped, warnings, coupled_motion, ...
  nlohmann::json report;
};

/// Runs one handclasp stage on `cell` with the section of `scenario` and the controllers'
/// flange models `pendant_models_flange` (nominal or calibrated; the scenario's tips are added
/// as tools), then scores it against cell.Truth(). Progress lines go to `progress`. Throws
/// InputError for a bad section; procedure failures are reported (ok = false, report.status).
HandclaspStageResult RunHandclaspStage(TwinCell& cell, const Scenario& scenario,
                                       const std::array<KinematicModel, 2>& pendant_models_flange,
                                       std::ostream& progress);

/// Loads the scenario, runs its handclasp section with the nominal models for each trial of
/// the batch and writes out_dir/report.json atomically (temporary file, then rename). Returns
/// 0 when every trial calibrated, 1 otherwise (the report says why). Throws InputError for bad
/// input (the CLI maps it to exit code 2).
int RunHandclaspScenario(const std::string& scenario_path, const std::string& out_dir,
                         std::ostream& progress);
/// As above, with progress on std::cerr.
int RunHandclaspScenario(const std::string& scenario_path, const std::string& out_dir);

}  // namespace twin
