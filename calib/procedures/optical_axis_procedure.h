// The whole optical-axis self-calibration of a dual-robot cell (Zhu et al. 2019, section VI),
// run through the Cell interface exactly as on hardware:
//   1. camera intrinsics by Zhang's method from board views (section VI.A);
//   2. for each robot to calibrate (the passive robot, carrying the board), with the camera on
//      the other (the active robot): PSO pose planning (section IV, eq. 24-41), then for each
//      optical axis, the active robot to its pose and the passive robot servoed onto the axis
//      at each planned position (section V.A, eq. 42-43; the measurement steps 1-5 of VI.C);
//   3. split by whole optical axes into calibration and validation sets (VI.C: 30 / 20);
//   4. identification on the calibration set (section V.B): the paper's linearized recursive
//      LM (eq. 45-49) and the Ceres formulation with nuisance lines plus the scale measurement
//      (nonlinear_identification.h); the mean misaligned error (eq. 46) before and after on both
//      sets;
//   5. the roles exchanged (Cell::ExchangeTools) and the other robot calibrated.
// Estimator side only: what it knows is CellKnowledge (nominal models, rough transforms, the
// board as printed and mounted by drawing); nothing of the truth.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "calib/cell/cell.h"
#include "calib/vision/feature_detector.h"
#include "calib/vision/intrinsics_calibration.h"
#include "calib/identification/identification_covariance.h"
#include "calib/identification/linearized_identification.h"
#include "calib/identification/nonlinear_identification.h"
#include "calib/planning/plan_store.h"
#include "calib/planning/pose_planner.h"
#include "calib/vision/visual_servo.h"

namespace twin {

/// What the estimator is told about the cell (section VI.B): nothing needs to be accurate
/// except the printed board.
struct CellKnowledge {
  std::array<KinematicModel, 2> nominal;  ///< the controllers' nominal models (flange = L6;
                                          ///< their tool link is not used)
  Transform X_B1B2 = Transform::Identity();  ///< rough pose of robot 2's base in robot 1's
  Transform X_FC = Transform::Identity();    ///< rough hand-eye: camera optical frame in the
                                             ///< flange (the same bracket on either robot)
  Transform X_FT = Transform::Identity();    ///< board mount by drawing: board frame (origin at
                                             ///< the feature point, z out of the face) in the
                                             ///< flange; link 7 of the passive model
  BoardGeometry board;                       ///< the printed board
  /// A larger printed chessboard for the intrinsics step (Cell::MountTarget), by drawing;
  /// absent: Zhang's method uses the board's few corners.
  std::optional<BoardGeometry> intrinsics_target;
};

/// Options of RunOpticalAxisCalibration. Defaults are the paper's where it gives them.
struct OpticalAxisOptions {
  std::vector<int> robots = {1, 0};  ///< robots to calibrate (passive), in this order
  int intrinsics_views = 40;         ///< board views for Zhang's method [-]
  IntrinsicsOptions intrinsics;      ///< options of CalibrateIntrinsics
  std::uint64_t seed = 1;            ///< seed of the intrinsics view poses (the planner and the
                                     ///< servo's IK restarts have their own, planner.seed and
                                     ///< servo.ik_seed)
  PosePlannerOptions planner;        ///< PSO (q, p, swarm, iterations, runs, C1-C5)
  /// Where the planner's IK starts (PosePlannerOptions::active_ik_seed): the mid-range of the
  /// joint limits (false, the default), or the joints both robots are read at when the
  /// procedure starts (true: the set-up pose; for arms whose joints turn a full turn or more).
  bool plan_from_start_pose = false;
  ServoOptions servo;                ///< alignment (tolerance 0.1 px, iteration limit)
  int calibration_axes = 3;          ///< axes in the calibration set, the rest validate
                                     ///< (paper: 30 / 20 poses of 5 x 10, by whole axes)
  /// Which whole axes calibrate: the first calibration_axes (kFirst), or the subset whose
  /// identification Jacobian has the highest identifiable rank and then the largest smallest
  /// identifiable singular value (kBestConditioned, the minimum-singular-value observability
  /// index: the weakest identifiable combination is determined best). The Jacobians are taken
  /// at the nominal model (RobotCalibration::split_at; taken at the fit of every usable axis,
  /// the rank-first rule picked subsets that reach a higher rank through weakly seen
  /// directions, and on the ABB their models missed the held-out axes, README.md of e5af83d).
  enum class Split { kFirst, kBestConditioned };
  Split split = Split::kBestConditioned;
  /// After the hold-out validation (the paper's metric, eq. 46, on the validation axes), the
  /// delivered model is identified again from all aligned axes (true), as one refits on all
  /// data after cross-validation; false delivers the calibration-set model.
  bool refit_all_axes = true;
  /// An aligned pose's board pose is tested before it becomes a sample: the refined pose's
  /// reprojection residuals over the board's corners against the corner noise the intrinsics
  /// step measured (chi-square, 2 N - 6 degrees of freedom). A corner the detector misplaced
  /// (an occluding edge, a highlight) bends the pose: its depth and its offset from the axis
  /// are then wrong by far more than their stated sigmas, and one such pose can move the
  /// identified scale by 1e-3 (README.md of e5af83d). A pose whose p-value is below this is left
  /// out (FailedPose "board_pose_inconsistent"); 0 keeps every pose.
  double board_pose_test_p = 1e-6;
  /// Start each position of an axis with the correction the servo found at the previous one
  /// (the kinematic error changes little over 20 mm), so the servo starts close.
  bool carry_correction = true;
  /// Start each axis's first position (and any position before one of its axis aligned)
  /// shifted by the plan's miss predicted from the positions aligned so far
  /// (AxisStartPredictor: a small rigid motion of the passive base, the rough base's error
  /// mostly), so a rough base does not put every axis a long way off.
  bool predict_axis_start = true;
  /// Servo moves commanded through a step model learnt over each robot's poses
  /// (ServoStepModel), so that first moves land within tolerance more often.
  bool learn_servo_steps = true;
  LinearizedIdentificationOptions linearized;  ///< the paper's method
  /// The paper's method stacks every pair of samples of an axis (eq. 22: 3 rows of 5 (N + 1)
  /// doubles each, ~840 bytes per pair for a six-axis arm), quadratic in the samples; above
  /// this many pairs it is skipped (status "skipped") and the engine alone identifies, whose
  /// cost is linear in the samples.
  int linearized_max_pairs = 200000;
  NonlinearIdentificationOptions nonlinear;    ///< Ceres, with the scale measurement
  int kept_images = 3;               ///< servo before/after image pairs kept per robot
  /// Optional: plans looked up before planning and kept after (a study's trials that are told
  /// the same share one plan); null plans every time.
  std::shared_ptr<PlanStore> plan_store;
  /// Progress lines (one per aligned pose, stage changes); may be empty.
  std::function<void(const std::string&)> progress;
};

/// Throws InputError for a calibration_axes outside 1..planner.num_axes (a scenario's
/// calibration.calibration_axes is unbounded where it is read) and for the values the nested
/// validators leave to the user (planner.min_distance, servo.gain); PreconditionError naming
/// any other bad field and value (the scenario's other keys are bounded where they are read).
void ValidateOpticalAxisOptions(const OpticalAxisOptions& options);

/// The passive robot's estimator model: the nominal model with link 7 the board mount (Zhu et
/// al. 2019, VI.A: "the calibration target is considered as the link 7"): link 7 holds the
/// mount's translation as eq. 2 parameters (theta = atan2(y, x), d = z, a = distance from the
/// flange axis, alpha = beta = 0) and X_LtE its rotation, so that L7 X_LtE = X_FT: the end
/// frame E is the board frame, origin the feature point, and link 7's parameters move that
/// point in every direction to first order.
KinematicModel BoardRobotModel(const KinematicModel& nominal, const Transform& X_FT);

/// One aligned pose: what a hardware cell records (measurements.csv).
struct AlignedPose {
  int axis = 0;                       ///< optical axis index of the plan
  int index = 0;                      ///< position index on the axis (0 = nearest)
  JointVector q_passive;  ///< recorded passive joint angles [rad]
  JointVector q_active;   ///< active joint angles (encoders) [rad]
  cv::Point2d pixel_error{0, 0};      ///< final (du, dv) [px]
  Vector3 p_C = Vector3::Zero();      ///< feature point in the camera frame from the board
                                      ///< pose (solvePnP, known square) [m]
  Vector3 offset = Vector3::Zero();   ///< AxisSample::offset: (p_C.x, p_C.y, 0) in Bp [m]
  double pose_rms_px = 0.0;           ///< the board pose's RMS reprojection error [px]
  int frames = 0;                     ///< images grabbed for this pose
  int moves = 0;                      ///< corrective moves
  int region_frames = 0;              ///< of `frames`, regions (ServoResult)
  int full_frame_fallbacks = 0;       ///< regions without the board
  cv::Point2d first_pixel_error{0, 0};  ///< (du, dv) of the first image [px]
  double time_s = std::numeric_limits<double>::quiet_NaN();  ///< the cell's clock [s]; NaN none
  /// The robot's temperature reading less RobotCalibration::temperature_reference_C [K]; NaN:
  /// no sensor.
  double temperature_delta_K = std::numeric_limits<double>::quiet_NaN();
};

/// One pose the servo could not align; skipped, the run goes on.
struct FailedPose {
  int axis = 0;
  int index = 0;
  std::string status;  ///< ServoStatus name or "active_move_failed"
  std::string reason;
  int frames = 0;
};

/// Misaligned error (eq. 46) of one set, nominal vs identified [m].
struct MisalignedSummary {
  double before = 0.0;
  double after = 0.0;
  int samples = 0;
};

/// A servo image pair for reports (Zhu et al. 2019, Fig. 12).
struct ServoImages {
  int axis = 0, index = 0;
  cv::Mat before, after;
  cv::Point2d error_before{0, 0}, error_after{0, 0};  ///< (du, dv) [px]
};

/// The last image of a pose whose board pose failed its test (OpticalAxisOptions::
/// board_pose_test_p), for the report: what the detector found and how the pose fits it.
struct RefusedPoseImage {
  int axis = 0, index = 0;
  cv::Mat image;                             ///< as grabbed (a region or the whole frame)
  cv::Point origin{0, 0};                    ///< the image's top-left pixel in the frame
  std::vector<cv::Point2d> detected;         ///< detected corners, frame coordinates [px]
  std::vector<cv::Point2d> reprojected;      ///< the pose's reprojection of them [px]
  double rms_px = 0.0;                       ///< RMS of their differences [px]
};

/// Everything about one calibrated (passive) robot.
struct RobotCalibration {
  int robot = 0;                       ///< passive robot index
  int camera_robot = 1;                ///< active robot index
  KinematicModel nominal;              ///< BoardRobotModel of the nominal model
  PosePlanResult plan;
  bool plan_from_store = false;        ///< the plan came from options.plan_store
  std::vector<AlignedPose> aligned;
  std::vector<FailedPose> failed;
  std::vector<AxisSample> samples;     ///< all aligned poses, axis = plan axis index
  /// The robot's temperature sensor (Cell::ReadTemperatureC) at its first aligned pose [deg C];
  /// each sample's temperature_delta_K is its reading less this one. NaN: no sensor.
  double temperature_reference_C = std::numeric_limits<double>::quiet_NaN();
  std::vector<int> calibration_axes;   ///< plan axis indices in the calibration set
  std::vector<int> validation_axes;    ///< ... in the validation set
  /// kBestConditioned: each candidate calibration subset (plan axes) and its smallest
  /// identifiable singular value (observability.h scaling); empty for kFirst.
  std::vector<std::pair<std::vector<int>, double>> split_candidates;
  /// Where the split's identifiability was evaluated: "nominal model".
  std::string split_at;
  LinearizedIdentificationResult linearized;  ///< paper, eq. 45-49, on the calibration set
  NonlinearIdentificationResult nonlinear;    ///< Ceres + scale, on the calibration set
  KinematicModel identified;           ///< the delivered model (see refit_all_axes)
  std::string method;                  ///< "ceres_with_scale", "ceres", or "linearized",
                                       ///< with "_all_axes" appended after the refit
  KinematicModel holdout;              ///< the calibration-set model (nonlinear unless it
                                       ///< failed): what the misaligned errors are of
  bool refit = false;                  ///< identified is the all-axes refit
  NonlinearIdentificationResult refit_result;  ///< Ceres on all usable axes, when refit
  /// Covariance of the delivered model's identifiable coordinates (the refit's, or the
  /// calibration-set Ceres solution's; not ok for the linearized fallback).
  IdentificationCovariance covariance;
  MisalignedSummary calibration_error, validation_error;  ///< eq. 46
  std::vector<MisalignedSummary> per_axis;  ///< per plan axis (samples 0 when dropped)
  std::vector<ServoImages> images;
  std::vector<RefusedPoseImage> refused_images;  ///< at most kept_images
  /// Wall times [s]: planning_s is how long the procedure waited for the plan (planning runs
  /// in the background from the start), plan_compute_s how long the planning itself took.
  double planning_s = 0, plan_compute_s = 0, servoing_s = 0, identification_s = 0;
};

/// Outcome of RunOpticalAxisCalibration.
struct OpticalAxisResult {
  IntrinsicsResult intrinsics;
  std::vector<RobotCalibration> robots;
  double intrinsics_s = 0;             ///< wall time of the intrinsics step [s]
};

/// Runs the procedure (header). Throws as ValidateOpticalAxisOptions for bad options,
/// PreconditionError for a bad board geometry, InputError for a bad nominal model, when the
/// camera does not see the board at the start (intrinsics), when planning finds no feasible
/// poses, or when too few poses align to identify (each message names the robot and step).
/// Failed single poses are skipped and listed.
OpticalAxisResult RunOpticalAxisCalibration(Cell& cell, const CellKnowledge& knowledge,
                                            const OpticalAxisOptions& options);

/// Splits plan axes 0..num_axes-1 into calibration and validation sets by whole axes:
/// options.calibration_axes of them calibrate, chosen by options.split among the axes with 3
/// or more samples (kBestConditioned: the identifiability of every subset at `at`,
/// NonlinearIdentifiability, and the one with the highest identifiable rank, then the largest
/// smallest identifiable singular value, wins; the procedure passes the nominal model,
/// RobotCalibration::split_at; `candidates` lists each subset
/// and that value, empty for kFirst or when there is no choice).
void SplitAxes(const KinematicModel& at, const std::vector<AxisSample>& samples,
               int num_axes, const OpticalAxisOptions& options,
               std::vector<int>* calibration_axes, std::vector<int>* validation_axes,
               std::vector<std::pair<std::vector<int>, double>>* candidates);

/// Identification of one robot from recorded samples (the part that runs on recorded data):
/// `samples` axis indices are plan axes; `calibration_axes` / `validation_axes` split them.
/// Fills linearized, nonlinear, holdout, the misaligned summaries and per_axis (all of the
/// calibration-set model), then identified and method (the refit on all axes when
/// options.refit_all_axes and there are validation axes, else the calibration-set model).
void IdentifyRobot(const std::vector<int>& calibration_axes,
                   const std::vector<int>& validation_axes, const OpticalAxisOptions& options,
                   RobotCalibration* robot);

}  // namespace twin
