// Generation of calibration poses for the two robots by particle swarm optimisation (Zhu et
// al. 2019, section IV: constraints C1-C5 eq. 24-33, index O1 eq. 34, PSO eq. 35-41).
//
// Estimator side only: it sees the nominal models, the rough base-to-base transform X_BaBp and
// the rough hand-eye X_FC. Frames: Ba/Bp active (camera) / passive (board) robot bases, F the
// active flange (DH frame L6), C the camera optical frame (+z = optical axis), E the passive end
// frame (the chessboard feature point).
//
// Particle (eq. 36-38), one sub-particle per optical axis k, all in Bp:
//   [P_c (3) | yaw, pitch of mu (2) | camera roll about mu (1) | D (1) | per position i:
//    board tilt a, tilt b, board roll (3)].
// mu is yaw/pitch away from the horizontal direction pointing from Ba towards Bp. The camera
// pose is P_c, mu and the roll; the active joint angles come from SolveIk on the active model's
// flange (camera origin + axis parameterisation: random draws then land near the passive robot,
// whereas random active joint angles almost never aim the camera at it). Positions are
// P_e(i) = P_c + (D + i D_step) mu, i = 0..p-1 (eq. 38 with 0-based i). The board's outward
// normal is -mu tilted by the rotation vector a x_C + b y_C (|(a, b)| = visibility angle, C3),
// then rolled about itself; passive joint angles come from SolveIk on the passive model.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "calib/kinematics/inverse_kinematics.h"
#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Options of PlanCalibrationPoses; defaults are the paper's (section VI.B, eq. 50).
struct PosePlannerOptions {
  int num_axes = 5;                    ///< q, optical axes [-]
  int positions_per_axis = 10;         ///< p, passive positions per axis [-] (>= 3)
  int swarm_size = 10;                 ///< N, particles [-]
  int iterations = 100;                ///< PSO iterations per run [-]
  int runs = 5;                        ///< independent PSO runs; one is returned (select_run) [-]
  /// Which run's best poses are returned: the lowest fitness 1/O1 (the paper's, kBestFitness),
  /// or the lowest predicted position error over the whole joint space (kPredictedError, see
  /// PredictedPositionError): O1 rewards a well-spread spectrum, not the error the
  /// identification leaves where the arm is used.
  enum class RunSelection { kBestFitness, kPredictedError };
  RunSelection select_run = RunSelection::kBestFitness;
  /// Random configurations (uniform in the joint limits) of PredictedPositionError, and their
  /// seed.
  int prediction_configurations = 200;
  std::uint64_t prediction_seed = 1;
  double inertia = 0.7;                ///< w of eq. 40 [-]
  double learning_personal = 1.5;      ///< L1 of eq. 40 [-]
  double learning_global = 1.5;        ///< L2 of eq. 40 [-]
  double max_velocity_fraction = 0.2;  ///< velocity clamp, fraction of each coordinate's range
  double min_joint_limit_distance = DegToRad(10.0);  ///< C1: min_i D_theta_i (eq. 24) [rad]
  double min_singular_value = 0.1;     ///< C2: smallest manipulator singular value (eq. 26)
  double max_visibility_angle = DegToRad(30.0);  ///< C3: angle board normal / axis (eq. 28) [rad]
  double min_distance = 0.3;           ///< C4: D_min of eq. 30 [m]
  double max_distance = 0.6;           ///< C5: D_max of eq. 33 [m]
  double planning_max_distance = 0.5;  ///< largest camera-board distance planned (D_max of VI.B) [m]
  double distance_step = 0.02;         ///< D_step of eq. 38 [m]
  double camera_reach = 0.4;           ///< camera region centre: this far from Ba towards Bp [m]
  double camera_height = 0.4;          ///< camera region centre: this high above Ba along Bp z [m]
  double camera_region_half_extent = 0.15;  ///< half side of the camera-origin box [m]
  double axis_cone_half_angle = DegToRad(40.0);  ///< largest yaw / pitch of mu [rad]
  Vector3 board_normal_in_E = Vector3::UnitZ();  ///< board's outward normal in E (unit) [-]
  /// Where each axis's IK starts (the active robot's camera pose, the passive robot's first
  /// board position; later positions start from the one before): empty is the mid-range of the
  /// joint limits (the default). A start configuration (the joints the cell was set up in)
  /// keeps every axis in that posture's branch: an arm whose joints turn a full turn or more
  /// (a UR's +-360 deg) has no posture at its mid-range, and mid-range seeds there give each
  /// axis its own branch and 2 pi wraps, so the moves between axes sweep the arm through
  /// itself. With a seed the IK makes no random restarts (a draw it cannot reach from the seed
  /// is replaced like any infeasible one) and each solution is turned by whole turns to the
  /// angles nearest the seed. Each given seed holds one angle per joint of its model.
  JointVector active_ik_seed;
  JointVector passive_ik_seed;
  /// Closed-form IK (calib/kinematics/spherical_wrist_ik.h) for a robot whose nominal model
  /// has a spherical wrist: of its answers, the one nearest the seed inside the limits (the
  /// same seeds as above), no iterations. Either robot without the structure, or a draw the
  /// closed form has no answer for inside the limits, gets the iterative solver. false (the
  /// default): the iterative solver for both. Its plans differ: its paired study on the paper
  /// scenario (docs/results/paired_studies.md) was not accepted.
  bool closed_form_ik = false;
  int max_draws_per_axis = 300;        ///< random draws of one sub-particle before giving up
  int redraws_after_update = 3;        ///< draws tried when an updated sub-particle is infeasible
  double rank_tolerance = 1e-6;        ///< relative singular-value cut of AnalyseObservability
  IkOptions ik = [] {
    IkOptions o;
    o.random_restarts = 3;  // draws are cheap to replace; a failed IK is the costly case
    return o;
  }();                                 ///< IK options for both robots
  std::uint64_t seed = 1;              ///< seed of all random numbers (reproducible)
  /// Threads running the independent PSO runs (0: one per CPU this process may use,
  /// UsableCpuCount). The result does not depend on it: every run has its own seed.
  int threads = 0;
  /// Optional: when it becomes true the runs stop and the result is kNoFeasiblePoses with
  /// reason "cancelled" (a procedure that failed elsewhere). Not an input of the plan.
  std::shared_ptr<std::atomic<bool>> cancel;
};

/// Throws InputError for a min_distance <= 0 (a scenario's calibration.planning.min_distance_mm
/// may be 0) and PreconditionError naming any other bad field and value (the scenario's keys
/// are bounded where they are read; the others no user sets). Geometric infeasibility (for
/// example min_distance > max_distance) is not an error: it gives kNoFeasiblePoses.
void ValidatePosePlannerOptions(const PosePlannerOptions& options);

enum class PosePlannerStatus {
  kSuccess,           ///< a feasible pose set was found and optimised
  kNoFeasiblePoses,   ///< no draw satisfied C1-C5 (see reason and rejections)
};

/// Name of a status ("success", "no_feasible_poses").
const char* ToString(PosePlannerStatus status);

/// Rejected draws / updates per cause; each infeasible sub-particle counts once, for the first
/// failed check in the order below.
struct RejectionCounts {
  int active_ik = 0;   ///< camera pose not reachable by the active robot
  int passive_ik = 0;  ///< a board pose not reachable by the passive robot
  int c1_joint_limits = 0;   ///< eq. 25
  int c2_singularity = 0;    ///< eq. 27
  int c3_visibility = 0;     ///< eq. 29
  int c4_min_distance = 0;   ///< eq. 30
  int c5_max_distance = 0;   ///< eq. 33
  int total() const;
};

/// The planned poses of one optical axis.
struct PlannedAxis {
  Vector3 camera_origin = Vector3::Zero();  ///< P_c in Bp [m]
  Vector3 direction = Vector3::UnitX();     ///< mu, unit, in Bp [-]
  JointVector q_active;                     ///< active robot joint angles [rad]
  std::vector<JointVector> q_passive;       ///< p passive joint angles [rad]
  std::vector<double> distances;            ///< planned D of each position [m]
};

/// Outcome of PlanCalibrationPoses.
struct PosePlanResult {
  PosePlannerStatus status = PosePlannerStatus::kNoFeasiblePoses;
  std::string reason;                       ///< cause when status != kSuccess
  std::vector<PlannedAxis> axes;            ///< q axes of the best particle (empty on failure)
  double best_fitness = 0.0;                ///< f_ob = 1/O1 of eq. 39 of the returned poses
  int best_run = -1;                        ///< run that produced the returned poses
  std::vector<double> run_fitness;          ///< each run's best fitness 1/O1
  std::vector<double> run_predicted_error;  ///< each run's PredictedPositionError [m]
  /// each run's PredictedPositionError in the similarity gauge [m]
  std::vector<double> run_predicted_similarity_error;
  /// Best fitness of each run after initialisation ([0]) and after every iteration (Fig. 10).
  std::vector<std::vector<double>> fitness_history;
  RejectionCounts rejections;               ///< all runs together
  int evaluations = 0;                      ///< sub-particle feasibility checks performed
};

/// Eq. 35-41: poses of both robots for `options.num_axes` optical axes that satisfy C1-C5 in the
/// nominal models and minimise 1/O1 of the passive robot's profiled identification matrix
/// (O1 over its identifiable singular values, LineConstraintInvariants removed).
/// X_BaBp: passive base in active base; X_FC: camera optical frame in the active flange.
PosePlanResult PlanCalibrationPoses(const KinematicModel& active, const KinematicModel& passive,
                                    const Transform& X_BaBp, const Transform& X_FC,
                                    const PosePlannerOptions& options = {});

/// The position error the identification from `axes` is expected to leave, RMS over
/// `configurations` random joint configurations uniform in the passive model's limits (seeded)
/// [m]: the samples the plan asks for (each planned position on its axis, its planned distance
/// as the measured depth), the covariance of the identifiable combinations of IdentifyNonlinear's
/// problem at the nominal model under its starting noise model (0.02 mm across the axis,
/// 0.1 mm in depth; NonlinearIdentifiability), propagated through the end point's parameter
/// Jacobian. The unidentifiable combinations (rigid motions of the arm) contribute nothing.
/// +infinity when nothing is identifiable.
/// `gauge`: kRaw is the error as it is; kRigid and kSimilarity first remove, from the stacked
/// errors of all configurations together, what one rigid motion (6) or one similarity (7: with
/// a scale about B's origin) of the end points explains: the error the bench's truth figures
/// score after those gauges (bench/scoring), whose differences between plans the raw figure
/// hides under the scale's share, the same for every plan of the same depths.
enum class PredictionGauge { kRaw, kRigid, kSimilarity };
double PredictedPositionError(const KinematicModel& passive, const std::vector<PlannedAxis>& axes,
                              double rank_tolerance, int configurations, std::uint64_t seed,
                              PredictionGauge gauge = PredictionGauge::kRaw);

/// Fitness of eq. 39 (1/O1; +infinity when O1 = 0) for given passive joint angles per axis and
/// axis directions mu_k in Bp.
double PoseSetFitness(const KinematicModel& passive,
                      const std::vector<std::vector<JointVector>>& q_passive,
                      const std::vector<Vector3>& directions, double rank_tolerance);

}  // namespace twin
