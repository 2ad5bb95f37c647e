// The handclasp base-frame calibration of Gan, Dai, Dong 2014 run on the MuJoCo twin: parses a
// scenario's `handclasp:` section, runs calib's procedure (calib/procedures/handclasp_procedure.h) on a
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
//     calibrated_operator_error_mm: 0.1  # the dual-arm workflow's second handclasp (with the
//                                  # calibrated kinematics, bench/runs/workflow_run.h): operator
//                                  # alignment error sigma per axis [mm] (default 0.1)
//     calibrated_tip_identification: true  # that handclasp teaches 4 tip orientations per
//                                  # point and identifies both tips on their flanges jointly
//                                  # with X_B1B2 (calib/identification/tip_refinement.h; default true)
//
// Taught points are the operator's choice: the planner uses the layout as drawn
// (rough_base_from_robot1) only to pick reachable points; the estimator gets contact joint
// readings alone. What is told (rough_base_from_robot1, tips, points, constraint) and what
// only the twin knows (scenario.robots[*].base*, scenario.tips, operator_error_mm: the
// simulated operator's accuracy) are kept apart: tests/bench/told_versus_true_test.cc changes
// every truth-only value and requires the told inputs unchanged.
// Plausibility limits: at most 100 points, each within 5 m of robot 1's base (the arms reach
// 1-4 m); operator errors at most 10 mm per axis (beyond it the tips do not touch); the told
// layout within 20 m, the told tips within 1 m of their flanges (as the twin's).
#pragma once

#include <array>
#include <limits>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "bench/io/scenario.h"
#include "bench/runs/bench_cell.h"
#include "bench/scoring/handclasp_results.h"
#include "calib/identification/base_calibration.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/procedures/handclasp_procedure.h"
#include "sim/cell/twin_cell.h"

namespace twin {

/// The `handclasp:` section, in SI units.
struct HandclaspConfig {
  /// Told: the layout as drawn, X_B1B2 the operator plans the taught points from.
  Transform rough_X_B1B2 = Transform::Identity();
  /// Told: each pendant's tip frame in its flange by drawing (X_FTip).
  std::array<Transform, 2> told_X_FTip = {Transform::Identity(), Transform::Identity()};
  bool auto_points = true;             ///< plan the points (else points_B1)
  std::vector<Vector3> points_B1;      ///< contact points in B1 [m] when !auto_points
  double operator_error_m = 0.0;       ///< alignment error sigma per axis [m] (the twin's
                                       ///< simulated operator: truth side)
  BaseConstraint constraint = BaseConstraint::kGeneral;  ///< resolved (never "auto")
  int trials = 1;                      ///< seeded batch size (>= 1)
  bool coupled_motion = true;          ///< run the coupled-motion check
  double calibrated_operator_error_m = 1e-4;  ///< workflow stage (c) alignment error [m]
  bool calibrated_tip_identification = true;  ///< workflow stage (c) identifies the tips
};

/// How one handclasp stage runs and is scored.
struct HandclaspStageOptions {
  /// Replaces the section's operator_error_mm when set [m].
  std::optional<double> operator_error_m;
  /// Teach 4 orientations per point and identify the tips (HandclaspOptions::identify_tips).
  bool identify_tips = false;
  /// Score in the best-fit frames of the pendant models (BestFitBaseOffset) instead of the
  /// link-1 frames (KinematicBaseOffset): for calibrated models, whose base gauge is not the
  /// link-1 one.
  bool best_fit_frames = false;
};

/// The constraint implied by the installations: robot 1 on the floor and robot 2 on the floor,
/// a wall or the ceiling give floor-floor, floor-wall, floor-ceiling; anything else general.
BaseConstraint ImpliedConstraint(const TwinSpec& twin);

/// Parses scenario.handclasp. Throws InputError naming "file:line scenario.handclasp.key" for
/// an absent section or told value, unknown keys and bad values.
HandclaspConfig ParseHandclaspConfig(const Scenario& scenario);

/// The scoring frame (bench only). A robot's geometry errors in link 1's theta and d are a
/// rotation of the whole arm about base z and a shift along it: no kinematic calibration can
/// see them (calib/identification/nonlinear_identification.h: they stay unidentifiable), so a controller's
/// model expresses its tip in a frame B' of its own, not in the physical base frame B. With
/// eq. 2's link transform RotZ(theta) TransZ(d) TransX(a) RotX(alpha) RotY(beta), and RotZ,
/// TransZ commuting,
///   FK_true(q) = X_BL0 RotZ(dtheta1) TransZ(dd1) X_BL0^-1 * FK_model(q),
/// where FK_model carries the pendant model's link-1 theta and d and the true rest, and
/// dtheta1 = theta1_true - theta1_pendant, dd1 = d1_true - d1_pendant. That is X_BB'; it is
/// exact for the link-1 part and gauge only (the other parameters' errors are what the
/// handclasp is expected to suffer from).
Transform KinematicBaseOffset(const KinematicModel& true_model,
                              const KinematicModel& pendant_model);

/// The frame B' a pendant model works in, for models whose base gauge is not link 1's theta
/// and d alone (after an optical-axis calibration the unidentifiable combinations also hold
/// link 1's beta, a rotation about a second vertical axis): the rigid X_BB' that best maps the
/// model's tip positions onto the true ones (least squares, Umeyama) over `configurations`
/// seeded random joint configurations inside the limits, with the tip corrections dt_F (in
/// the flange frame, e.g. identified by the handclasp) applied to the model's tip. With a
/// calibration exact in its identifiable combinations this is the exact gauge; otherwise the
/// remaining model error is what the handclasp suffers from.
Transform BestFitBaseOffset(const KinematicModel& true_tip_model,
                            const KinematicModel& pendant_tip_model, const Vector3& dt_F,
                            int configurations = 200);

/// X_B1'B2' = X_B1B1'^-1 X_B1B2 X_B2B2': the transform between the frames the robots'
/// kinematic models (the pendant models) use; what a handclasp can determine at best and what
/// base_frame.{general,constrained} are scored against. The physical X_B1B2 is scored too
/// (base_frame.physical_truth).
Transform KinematicFrameTruth(const TwinTruth& truth,
                              const std::array<KinematicModel, 2>& pendant_models);

/// The operator's teaching options of a stage: the planner's defaults
/// (calib/procedures/handclasp_procedure.h) with its IK restarts seeded by the scenario's
/// estimator seed, and 4 tip orientations per point where the tips are identified.
TeachOptions HandclaspTeachOptions(const Scenario& scenario, bool identify_tips);

/// The points a stage teaches before its first contact, from told values alone: the told tips
/// (config.told_X_FTip) as tools of the flange models `pendant_models_flange`, the layout as
/// drawn (config.rough_X_B1B2), the planned cube (points: auto, PlanTaughtPoints) or the listed
/// points (TeachPoints), IK seeded at `seeds` (robot 1's and robot 2's encoders). Needs no
/// twin: `twinbench new-scenario` (bench/scaffold/new_scenario.h) and its tests call it with
/// the nominal models at the initial joints, which the settled encoders read to the sag.
TaughtPoints TeachHandclaspPoints(const HandclaspConfig& config,
                                  const std::array<KinematicModel, 2>& pendant_models_flange,
                                  const std::array<JointVector, 2>& seeds,
                                  const TeachOptions& options);

/// Runs one handclasp stage on `cell` with the section of `scenario` and the controllers'
/// flange models `pendant_models_flange` (nominal or calibrated; the section's told tips are
/// added as tools), then scores it against cell.Truth() (bench/scoring/handclasp_results.h;
/// bench/report/handclasp_report.h writes it). Progress lines go to `progress`. Throws
/// InputError for a bad section; procedure failures are reported (ok() false, status, reason).
HandclaspStageResult RunHandclaspStage(BenchCell& cell, const Scenario& scenario,
                                       const std::array<KinematicModel, 2>& pendant_models_flange,
                                       std::ostream& progress,
                                       const HandclaspStageOptions& stage_options = {});
/// As above, on the twin in this process.
HandclaspStageResult RunHandclaspStage(TwinCell& cell, const Scenario& scenario,
                                       const std::array<KinematicModel, 2>& pendant_models_flange,
                                       std::ostream& progress,
                                       const HandclaspStageOptions& stage_options = {});

/// Loads the scenario, runs its handclasp section with the nominal models for each trial of
/// the batch and writes out_dir/report.json through a staging folder (renamed onto out_dir
/// when complete). Returns 0, or 3 when the scenario's acceptance criteria are missed
/// (bench/report/acceptance.h; `junit` names the JUnit file to write, empty for none). Throws
/// InputError for bad input and when a trial's procedure refused (which trial and why; the
/// CLI maps it to exit code 2, nothing is written then). `trial` offsets both seeds
/// (ApplyTrial).
int RunHandclaspScenario(const std::string& scenario_path, const std::string& out_dir,
                         std::ostream& progress, int trial = 0, const std::string& junit = "");
struct RunOptions;  // bench/runs/calibration_run.h
/// As above with the run's options: on the cell options.cell names (a served cell, a
/// recording, a replay: one trial, InputError otherwise, before anything moves; on a cell
/// without truth the estimates alone), progress on std::cerr.
int RunHandclaspScenario(const RunOptions& options);
/// As above, with progress on std::cerr.
int RunHandclaspScenario(const std::string& scenario_path, const std::string& out_dir);

}  // namespace twin
