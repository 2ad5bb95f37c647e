// Image-based visual control that puts the chessboard's feature point P on the camera's optical
// axis by moving the passive robot (Zhu et al. 2019, section V.A, eq. 42-44). It talks to the
// cell only through calib/cell/cell.h and uses only estimator-side knowledge: nominal models, rough
// base-to-base and hand-eye rotations, estimated intrinsics and the printed board geometry.
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "calib/cell/cell.h"
#include "calib/vision/feature_detector.h"
#include "calib/common/frames.h"
#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// Estimated pinhole intrinsics (eq. 44), OpenCV pixel convention [px].
struct PinholeIntrinsics {
  double fx = 834.31;  ///< k_x, focal length in pixels along u [px]
  double fy = 833.38;  ///< k_y, focal length in pixels along v [px]
  double cx = 513.56;  ///< u_0, principal point column [px]
  double cy = 403.95;  ///< v_0, principal point row [px]
};

/// What the estimator knows for the servo; none of it needs to be accurate (section V.A).
struct ServoSetup {
  KinematicModel active_model;              ///< nominal model of the camera robot
  KinematicModel passive_model;             ///< nominal model of the board robot
  int passive_robot = 1;                    ///< cell index of the passive robot; active = 1 - it
  Matrix3 R_BaBp = Matrix3::Identity();     ///< rough rotation of the passive base Bp in the
                                            ///< active base Ba
  Matrix3 R_FC = Matrix3::Identity();       ///< rough hand-eye: camera C in the active flange F
  PinholeIntrinsics intrinsics;             ///< estimated intrinsics
  BoardGeometry board;                      ///< the printed board
  JointVector q_active;  ///< active robot's encoder reading [rad]
};

/// Options of AlignFeatureToOpticalAxis.
struct ServoOptions {
  double tolerance_px = 0.1;   ///< aligned when |du| and |dv| are below this (paper: 0.1) [px]
  int max_iterations = 10;     ///< corrective moves before giving up (images: one more) [-]
  double gain = 1.0;           ///< fraction of the estimated correction applied per move, (0, 2)
  double nominal_depth_m = 0;  ///< depth z_f of P [m]; 0 estimates it per image with solvePnP
  /// Largest translation of one move [m]; a longer correction is taken in moves of this
  /// length, each followed by a new image (within max_iterations).
  double max_step_m = 0.05;
  std::uint64_t ik_seed = 1;   ///< seed of nominal IK's random restarts (reproducible)
  /// Readings of the passive encoders averaged for ServoResult::q_passive, the arm at rest at
  /// the final pose (a controller reads them every cycle): jitter independent per reading
  /// falls by sqrt(N), a quantization without jitter does not. 1: one reading (the paper's).
  int encoder_readings = 1;
  /// After a detection, grab only the region where the board will be (Cell::GrabImageRegion,
  /// board_region.h); a whole frame when the board is not found there (and first, unless a
  /// first region is given).
  bool use_regions = true;
  double region_margin_squares = 2.0;  ///< region grown by this many squares per side [-]
  double region_slack_px = 12.0;       ///< and by this much for the prediction's error [px]
};

/// Throws InputError for a gain outside (0, 2) (a scenario's calibration.servo.gain may be 2),
/// PreconditionError naming any other bad field and value (the scenario's servo keys are
/// bounded where they are read; the others no user sets).
void ValidateServoOptions(const ServoOptions& options);

/// What the servo learns of its own moves: how the image of P moves when it commands a motion
/// of c pixels, observed = M c. With rough rotations (hand-eye, base) M is a rotation and
/// scale a few percent off the identity, so a single move from a few pixels misses 0.1 px;
/// M is fitted by least squares to the (commanded, observed) pairs of earlier moves and
/// regularized toward the identity. One model per calibrated robot carries over its poses and
/// axes (the rough hand-eye error is the same in every image).
struct ServoStepModel {
  Eigen::Matrix2d sum_oc = Eigen::Matrix2d::Zero();  ///< sum of observed c^T [px^2]
  Eigen::Matrix2d sum_cc = Eigen::Matrix2d::Zero();  ///< sum of c c^T [px^2]
  int pairs = 0;                                     ///< moves learnt from
  /// M = (sum_oc + w I)(sum_cc + w I)^-1, w = prior_px^2 (the identity weighs as much as a
  /// move of prior_px in each direction).
  Eigen::Matrix2d Matrix(double prior_px) const;
  /// Adds a move that commanded c and was observed to move the image by `observed` [px].
  void Add(const Eigen::Vector2d& c, const Eigen::Vector2d& observed);
};

enum class ServoStatus {
  kAligned,         ///< |du|, |dv| < tolerance_px
  kBoardNotFound,   ///< the feature point was not detected in an image
  kIkFailed,        ///< nominal IK found no joint angles for the corrected pose
  kMoveFailed,      ///< the cell refused or failed a move (collision, not settled, bad input)
  kJointLimits,     ///< a start or corrected pose lies outside the passive joint limits
  kNotConverged,    ///< still misaligned after max_iterations moves
};

/// Name of a status for messages ("aligned", "board_not_found", ...).
const char* ToString(ServoStatus status);

/// Outcome of AlignFeatureToOpticalAxis.
struct ServoResult {
  ServoStatus status = ServoStatus::kNotConverged;
  std::string reason;                          ///< cause when not aligned, empty when aligned
  cv::Point2d pixel_error{0, 0};               ///< last measured (du, dv) = (u - cx, v - cy) [px]
  int frames = 0;                              ///< images grabbed
  int moves = 0;                               ///< corrective moves commanded
  JointVector q_passive;  ///< final passive encoder reading, mean of encoder_readings [rad]
  /// Sign of each passive joint's last commanded motion over the corrections (+1, -1; 0: no
  /// correction moved it), each target against the one before, the start pose first: the
  /// approach direction a backlash acts with.
  JointVector approach;
  cv::Mat image_before;                        ///< first image grabbed (reports)
  cv::Mat image_after;                         ///< last image grabbed (reports)
  cv::Point2d first_pixel_error{0, 0};         ///< (du, dv) of the first image [px]
  cv::Point image_before_origin{0, 0};         ///< frame pixel of image_before's (0, 0)
  cv::Point image_after_origin{0, 0};          ///< frame pixel of image_after's (0, 0)
  FeatureDetection detection_after;            ///< of the last image, frame coordinates
  int region_frames = 0;                       ///< of `frames`, regions (GrabImageRegion)
  int full_frame_fallbacks = 0;                ///< regions without the board, then a frame
  int limited_moves = 0;  ///< of `moves`, corrections cut to max_step_m (a far start)
};

/// Moves the passive robot to q_passive_start, then repeats: grab an image, detect P, and if
/// (du, dv) (eq. 31) is not within tolerance move the passive end frame by -gain * dP_Bp with
/// dP_Bp = R_BpC (du z / fx, dv z / fy, 0) (eq. 42-43), keeping its nominal orientation, via
/// nominal IK seeded at the encoders. Never loops past max_iterations moves. Throws as
/// ValidateServoOptions for bad options, PreconditionError for a bad setup (robot index, board,
/// intrinsics); cell failures come back as a status.
/// With options.use_regions, `first_region` (frame pixels; empty: a whole frame) is where to
/// look in the first image (for example PredictBoardRegion of the previous pose's detection).
/// With `step_model` (optional, updated), each move commands M^-1 of the wanted image motion
/// and moves of at least 2 px teach the model (see ServoStepModel).
ServoResult AlignFeatureToOpticalAxis(Cell& cell, const ServoSetup& setup,
                                      const JointVector& q_passive_start,
                                      const ServoOptions& options = {},
                                      const cv::Rect& first_region = cv::Rect(),
                                      ServoStepModel* step_model = nullptr);

}  // namespace twin
