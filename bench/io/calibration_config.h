// The `calibration:` section of a scenario: what the estimator is told (rough base-to-base and
// hand-eye transforms, the board by drawing) and the options of the optical-axis procedure.
// Example (scenarios/paper_reinovo.yaml); every key is optional unless marked:
//
//   calibration:
//     robots: [r2, r1]                 # passive robots, in calibration order (default: the
//                                      # board robot, then the camera robot)
//     rough_base_from_robot1: {xyz_mm: [1200, 0, 0], zyz_deg: [180, 0, 0]}  # required
//     rough_hand_eye: {xyz_mm: [60, -60, -26], rpy_deg: [0, 0, 0]}       # required, X_FC
//     board_mount: {xyz_mm: [0, 0, 40], rpy_deg: [0, 0, 0]}  # required: X_FT by drawing
//     board_squares: [4, 4]            # required: the printed board (even counts, 2..30)
//     board_square_mm: 20              # required: its printed square side [1, 500] mm
//     board_mass_kg: 0.2               # the board with its bracket, as weighed (default 0:
//                                      # not told); a point mass at the feature point in the
//                                      # models of the diagnosis, whose gravity terms need it
//     intrinsics_target: {squares: [14, 10], square_mm: 20}  # a larger chessboard, by
//                                      # drawing, that the operator mounts on the board's
//                                      # bracket for Zhang's method and takes off after (the
//                                      # cell must have one: scenario.intrinsics_target);
//                                      # absent: the board itself (even counts, 2..30)
//     intrinsics_views: 25             # board views for Zhang's method
//     intrinsics_distortion: brown     # the lens model Zhang's method estimates: brown (k1, k2,
//                                      # p1, p2; k3 held at 0; the default) or none (a pinhole,
//                                      # as the paper's K of section VI.A; for a lens known to
//                                      # be distortion-free, where a 4x4 board's few corners
//                                      # let distortion trade against fx)
//     planning:                        # section IV and eq. 50 (defaults: the paper's)
//       axes: 5                        # q
//       positions_per_axis: 10         # p
//       swarm_size: 10
//       iterations: 100
//       runs: 5
//       distance_step_mm: 20           # D_step
//       planning_max_distance_mm: 500  # largest planned camera-board distance
//       min_distance_mm: 300           # C4
//       max_distance_mm: 600           # C5
//       min_joint_limit_distance_deg: 10   # C1
//       min_singular_value: 0.1        # C2
//       max_visibility_angle_deg: 30   # C3
//       camera_reach_mm: 400           # centre of the camera search box, from the active
//       camera_height_mm: 400          #   base towards the passive base and up
//       seed: 1                      # PSO seed, the same for every trial of a study (the
//                                    # plan is then planned once and cached); absent: the
//                                    # scenario's estimator seed (+ trial), see scenario.h
//       select_run: best_fitness       # which PSO run's poses: best_fitness (the paper's
//                                      # 1/O1) or predicted_error (PredictedPositionError,
//                                      # pose_planner.h)
//       ik_seed: mid_range             # where each axis's IK starts: mid_range (the joint
//                                      # limits' middle) or start_pose (the joints read when
//                                      # the procedure starts; for arms whose joints turn a
//                                      # full turn or more, e.g. a UR's +-360 deg)
//       ik: iterative                  # the planner's IK: iterative (damped least squares)
//                                      # or closed_form (an arm with a spherical wrist; the
//                                      # others stay iterative): other plans, paired study in
//                                      # docs/results/paired_studies.md
//     servo: {tolerance_px: 0.1, max_iterations: 10, gain: 1.0,
//             encoder_readings: 1}     # readings averaged at each aligned pose (at rest)
//     calibration_axes: 3              # whole axes in the calibration set; the rest validate
//     calibration_split: best_conditioned  # which axes: best_conditioned (the subset with the
//                                      # largest smallest identifiable singular value) or first
//     refit_all_axes: true             # deliver the model refit on all axes after validation
//                                      # (false: the calibration-set model)
//     board_pose_test_p: 1e-6          # an aligned pose whose board pose fails the chi-square
//                                      # test of its corner residuals at this level is left
//                                      # out (OpticalAxisOptions::board_pose_test_p; 0: off)
//     scoring: {configurations: 200, seed: 1}   # truth metrics (bench only)
//     diagnosis: {enabled: true, ...}  # model discovery per calibrated robot on its aligned
//                                      # poses (bench/io/diagnosis_config.h)
//
// Told versus true: the told values come from this section only. The twin's truth (the
// scenario's robots[1].base_from_robot1, camera.hand_eye and intrinsics, board.*) is never
// read for them; a missing told value is an error. The nominal models are the model files
// (the truth is them perturbed by the geometry effects). tests/bench/told_versus_true_test.cc
// changes every truth-only value of a scenario and requires this section's result unchanged.
// Plausibility limits (each with its reason in the message): told base within 20 m, told
// tools within 1 m; intrinsics_views 3..500; planning axes 1..20, positions 3..100, swarm
// 1..1000, iterations 1..10000, runs 1..100 and at most 1e5 evaluations in all; distances up
// to 5000 mm; servo tolerance 0.001..100 px, iterations 1..1000, gain 0.01..2; scoring
// configurations 10..100000.
// Errors are InputErrors naming file:line and the key path, like the rest of the scenario.
#pragma once

#include <cstdint>

#include "bench/io/diagnosis_config.h"
#include "bench/io/scenario.h"
#include "calib/procedures/optical_axis_procedure.h"

namespace twin {

/// The parsed `calibration:` section.
struct CalibrationConfig {
  CellKnowledge knowledge;       ///< what the estimator is told
  OpticalAxisOptions options;    ///< procedure options (progress left empty)
  int scoring_configurations = 200;   ///< random joint configurations for truth metrics
  std::uint64_t scoring_seed = 1;     ///< their seed
  double board_mass_kg = 0.0;         ///< told payload (weighed), for gravity terms
  DiagnosisConfig diagnosis;          ///< model discovery (calibration.diagnosis)
  /// Why it does not run when diagnosis.enabled is false (for the report).
  std::string diagnosis_skip_reason = "calibration.diagnosis.enabled: false";
  DiscoveryOptions discovery;         ///< its options (candidates checked on robot 1's model)
};

/// Parses scenario.calibration (an InputError when the section is absent or wrong). The
/// nominal models are the scenario's robot models (what the twin then perturbs).
CalibrationConfig ParseCalibrationConfig(const Scenario& scenario);

}  // namespace twin
