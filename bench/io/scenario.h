// Scenario files (scenarios/*.yaml): the edge where a YAML description of a twin cell becomes a
// TwinSpec. Units are in the key names (mm, deg, s, kg) and converted to SI on reading; paths
// are relative to the folder of the scenario file. Example (scenarios/twin_demo.yaml):
//
//   scenario:
//     format: 2                            # optional (default 1): the format version; see
//                                          # bench/io/scenario_keys.h for what 2 changed
//     name: twin_demo                      # required
//     seed: 7                              # optional (default 1): the seed of both random
//                                          # streams below (truth and estimator)
//     seeds: {truth: 7, estimator: 7}      # optional instead of seed (each default 1):
//                                          # truth: the twin's draws (geometry errors, effects,
//                                          # noise, the operator's error); estimator: the
//                                          # estimator's own randomness (intrinsics view poses,
//                                          # PSO planning unless calibration.planning.seed pins
//                                          # it, IK restarts, taught points). Trial t of a study
//                                          # (`twinbench run --trial t`) uses both + t.
//                                          # seeds.noise (optional, no default): the twin's
//                                          # draws while it runs (noise, the operator's error)
//                                          # from this seed instead of truth's: the same truth
//                                          # measured again; trial t adds t to it too
//     robots:                              # required: two, or one alone (a laser-tracker
//                                          # cell, below)
//       - name: r1                         # unique identifier ([A-Za-z_][A-Za-z0-9_]*), used by
//                                          # camera.robot, board.robot, tips and effects; it also
//                                          # renames the loaded model (parameter-name prefix)
//         model: ../models/reinovo_r1.yaml # required; LoadRobotModel (.yaml, .yml or .urdf)
//         base_link: base_link             # optional, URDF only: where the arm starts and
//         tip_link: tool0                  # ends (defaults: the root link; the leaf link with
//                                          # the most moving joints above it)
//         installation: floor              # required: floor | wall | ceiling
//         base: {xyz_mm: [0, 0, 0], rpy_deg: [0, 0, 0]}   # optional X_WB1 (default identity)
//         initial_joints_deg: [0, 34, -34, 0, 90, 90]    # required, 6 motor-side angles
//       - name: r2
//         model: ../models/reinovo_r2.yaml
//         installation: floor
//         base_from_robot1: {xyz_mm: [1200, 0, 0], zyz_deg: [180, 0, 0]}  # required X_B1B2;
//                                          # X_WB2 = X_WB1 X_B1B2 (robot 2 takes no 'base')
//         initial_joints_deg: [0, 39, -36, 0, 87, 90]
//     camera:                              # required with two robots (refused with one)
//       robot: r1                          # required: the robot whose flange carries it
//       hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 0, 0]}  # required X_FC (OpenCV optical C)
//       resolution: [1024, 768]            # required [width, height] px
//       fx: 834.31                         # required fx, fy, cx, cy [px]
//       fy: 833.38
//       cx: 513.56
//       cy: 403.95
//       distortion: [0, 0, 0, 0, 0]        # optional [k1, k2, p1, p2, k3] (default none)
//       msaa: 4                            # optional samples 0, 1, 2, 4, 8 (default 4)
//       skybox: true                       # optional: draw the sky behind the scene (default
//                                          # true; false: black, a quarter less to render)
//       near_mm: 20                        # optional clipping planes (defaults 20, 5000)
//       far_mm: 5000
//     board:                               # required with two robots (refused with one)
//       robot: r2                          # required
//       squares: [4, 4]                    # required [x, y] squares
//       square_mm: 20                      # required
//       margin_mm: 10                      # optional (default 10)
//       thickness_mm: 4                    # optional (default 4)
//       mass_kg: 0.2                       # optional (default 0.2)
//       mount: {xyz_mm: [0, 0, 40], rpy_deg: [0, 0, 0]}      # required X_FT
//     intrinsics_target:                   # optional, two robots: a larger chessboard the
//       squares: [14, 10]                  # operator swaps onto the board's bracket for the
//       square_mm: 20                      # intrinsics step (Cell::MountTarget); required in
//       margin_mm: 10                      # it: squares, square_mm; margin, thickness, mass and
//       thickness_mm: 5                    # mount as the board's (defaults: 10 mm, 4 mm, the
//       mass_kg: 0.6                       # board's mass and the board's mount); the
//                                          # estimator is told it by
//                                          # calibration.intrinsics_target
//     tips:                                # optional, keyed by robot name; each entry optional
//       r1: {xyz_mm: [0, 0, 80], rpy_deg: [0, 0, 0], length_mm: 80, radius_mm: 4}
//                                          # pose X_FTip (if given, xyz_mm and a rotation), and
//                                          # optional length_mm, radius_mm (defaults TipSpec;
//                                          # without a pose: at the flange's centre, pointing
//                                          # out of the face: RotX(180 deg) where the model's
//                                          # last d < 0, L_N's z into the wrist, as on KUKAs)
//     physics:                             # optional; each key optional (defaults PhysicsSpec)
//       timestep_s: 0.002
//       stiffness_Nm_per_rad: 1.0e5
//       armature_kgm2: 0.1
//       max_joint_speed_deg_s: 57.3
//       settle_speed_deg_s: 5.7e-5
//       settle_steps: 20
//       max_steps: 20000
//       gravity: true
//     calibration: {...}                   # optional, two robots: the optical-axis procedure
//                                          # (see bench/io/calibration_config.h)
//     handclasp: {...}                     # optional, two robots: the handclasp base-frame
//                                          # procedure (bench/runs/handclasp_run.h)
//     tracker:                             # optional: a laser tracker (truth; TrackerSpec)
//       robot: r2                          # the robot carrying the reflector
//       pose: {xyz_mm: [..], rpy_deg: [..]}  # the tracker frame in the world
//       reflector_mm: [30, -20, 60]        # the reflector in that robot's flange frame
//       sigma_mm: 0.01                     # optional (0.01): noise per axis
//       sigma_um_per_m: 0                  # optional: range-proportional noise
//       drift_mm_per_h: [0, 0, 0]          # optional: drift of the readings
//       max_range_m: 30                    # optional: range
//     tracker_calibration: {...}           # optional (required with one robot): the tracker
//                                          # procedure (told values; bench/runs/tracker_run.h)
//     acceptance:                          # optional: criteria on report.json figures that
//       - {figure: robots.r2.truth_position_error_mm.rigid.after.rms, max: 0.3}  # make
//                                          # `twinbench run` exit 3 when missed
//                                          # (bench/report/acceptance.h)
//     effects:                             # optional list, applied on the truth side
//       - type: transmission_error         # required; one of EffectTypes()
//         declared: false                  # optional (default true): told to the estimator?
//         robot: r2                        # optional robot name (absent: every robot)
//         joint: 3                         # optional joint 1..6 (absent: every joint)
//         amplitude_deg: 0.02              # every other key is a number, into EffectSpec::params
//         harmonic: 2                      #   under its own name (the effect checks its keys)
//
// A one-robot cell (scenarios/tracker_single_reinovo.yaml) is an arm alone with a laser
// tracker: `robots:` lists one robot, and the cell has no camera, board, intrinsics target or
// second robot (camera:, board:, intrinsics_target: and tips of another robot are refused).
// It runs only the tracker procedure: tracker_calibration: (with tracker:) is required, and
// calibration: and handclasp:, which need two robots, are refused. Effects act on its one robot
// (`robot:` absent or its name); image_noise and mount_deflection, which act through the camera
// and the board, are refused. For example:
//
//   scenario:
//     format: 2
//     name: tracker_single_reinovo
//     robots:
//       - name: r1
//         model: ../models/reinovo_r2.yaml
//         installation: floor
//         initial_joints_deg: [11.86, 21.16, -15.5, -64.86, 76.88, -25.73]
//     effects:
//       - {type: geometry_errors, sigma_length_mm: 2.0, sigma_angle_deg: 0.25}
//     tracker: {robot: r1, pose: {xyz_mm: [-2000, -400, 900], rpy_deg: [0, 0, -8]},
//               reflector_mm: [40.6, -29.2, 80.9]}
//     tracker_calibration: {robot: r1, told_reflector_mm: [40, -30, 80], poses: 100}
//
// A pose map takes xyz_mm and exactly one of rpy_deg (fixed axes, R = Rz(y) Ry(p) Rx(r), as
// URDF) or zyz_deg (R = Rz(a) Ry(b) Rz(c), the Euler angles of Gan et al. 2014, eq. 31).
// Everything is checked before anything runs: malformed YAML, unknown or missing keys, wrong
// list lengths, non-numeric values, unknown robot names, then ValidateTwinSpec and MakeEffect
// for each effect. Every error is an InputError whose where() is "file:line key.path" (e.g.
// "scenarios/twin_demo.yaml:31 scenario.board.square_mm") and whose message says what was
// expected.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bench/io/yaml_util.h"
#include "sim/world/twin_spec.h"

namespace twin {

/// The two independent random streams of a scenario (trial 0; ApplyTrial offsets them).
struct ScenarioSeeds {
  std::uint64_t truth = 1;      ///< the twin: geometry draws, effects, noise, the operator
  std::uint64_t estimator = 1;  ///< the estimator's own randomness (views, planning, IK)
  /// The twin's draws while it runs (noise, the operator's error) apart from `truth`'s
  /// geometry; absent: they come from `truth` (TwinSpec::noise_seed).
  std::optional<std::uint64_t> noise;
};

/// A loaded scenario: the twin cell it describes plus where it came from.
struct Scenario {
  std::string name;                                  ///< scenario.name
  std::string path;                                  ///< the file it was read from (source)
  int format = 1;                                    ///< scenario.format (1 where absent)
  TwinSpec twin;                                     ///< the cell, in SI units, validated;
                                                     ///< twin.seed == seeds.truth
  ScenarioSeeds seeds;                               ///< seeds of this trial
  int trial = 0;                                     ///< the trial (ApplyTrial), 0 as loaded
  std::vector<std::string> robot_names;  ///< robot names, in file order (twin.num_robots)
  std::vector<std::string> model_paths;  ///< model files as resolved and loaded, likewise
  std::vector<std::string> warnings;                 ///< the model imports' warnings, each
                                                     ///< naming its robot (LoadScenario prints
                                                     ///< them to stderr)
  /// The optional procedure sections, as written (node empty when absent); each procedure
  /// parses its own with YamlReader(path), so messages name file, line and key path:
  /// `calibration:` (optical-axis calibration, bench/io/calibration_config.h) and `handclasp:`
  /// (base-frame calibration by handclasp).
  YamlField calibration;
  YamlField handclasp;
  /// `tracker_calibration:` (the tracker procedure, bench/runs/tracker_run.h); the tracker
  /// itself (`tracker:`, truth) is parsed into twin.tracker.
  YamlField tracker_calibration;
  /// `acceptance:`, the CI verdict's criteria on report figures (bench/report/acceptance.h).
  YamlField acceptance;
};

/// Parses scenario text. `source` names it in messages; relative model paths are resolved
/// against `base_dir` (empty: the current directory). Throws InputError (see above).
Scenario ParseScenario(const std::string& text, const std::string& source,
                       const std::string& base_dir);

/// The format version of a scenario file's YAML (scenario.format, bench/io/scenario_keys.h): 1
/// where the key is absent (or the file is not a scenario map; the parser says why). Throws
/// InputError naming the file for a version that is not a whole number >= 1 or is newer than
/// kScenarioFormat (the message names the version and the newest known).
int ScenarioFormatOf(const YAML::Node& root, const std::string& source);

/// Prints, once per path and process, the notice for a scenario of an older format: which
/// version it was read as and what format 2 changed (ScenarioFormatNotice).
void PrintFormatNotice(const std::string& path, int format);

/// Reads and parses a scenario file; model paths are relative to the file's folder. A missing
/// or unreadable file is an InputError naming it. Prints the warnings to stderr, and the format
/// notice for a file without scenario.format (PrintFormatNotice).
Scenario LoadScenario(const std::string& path);

/// Throws InputError naming `section` of the scenario ("calibration", "handclasp") when its
/// cell has one robot: `what` (that procedure) needs two. The parser refuses such a section on
/// a one-robot cell already; procedures check again for scenarios built in code.
void RequireTwoRobots(const Scenario& scenario, const std::string& section,
                      const std::string& what);

/// Makes `scenario` trial `trial` of a study: both seeds become the file's seeds + trial
/// (twin.seed follows seeds.truth). Throws InputError ("--trial") for a negative trial.
void ApplyTrial(int trial, Scenario* scenario);

}  // namespace twin
