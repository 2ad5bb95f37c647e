// Image-based visual control that puts the chessboard's feature point P on the camera's optical
// axis by moving the passive robot (Zhu et al. 2019, section V.A, eq. 42-44). It talks to the
// cell only through calib/cell/cell.h and uses only estimator-side knowledge: nominal models, rough
// base-to-base and hand-eye rotations, estimated intrinsics and the printed board geometry.
#pragma once

#include <string>

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
  double max_step_m = 0.05;    ///< largest translation of one move; larger ones are refused [m]
};

/// Throws InputError naming the bad field and value.
void ValidateServoOptions(const ServoOptions& options);

enum class ServoStatus {
  kAligned,         ///< |du|, |dv| < tolerance_px
  kBoardNotFound,   ///< the feature point was not detected in an image
  kIkFailed,        ///< nominal IK found no joint angles for the corrected pose
  kMoveFailed,      ///< the cell refused or failed a move (collision, not settled, bad input)
  kJointLimits,     ///< a start or corrected pose lies outside the passive joint limits
  kNotConverged,    ///< still misaligned after max_iterations moves (or a step too large)
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
  JointVector q_passive;  ///< final passive encoder reading [rad]
  cv::Mat image_before;                        ///< first image grabbed (reports)
  cv::Mat image_after;                         ///< last image grabbed (reports)
};

/// Moves the passive robot to q_passive_start, then repeats: grab an image, detect P, and if
/// (du, dv) (eq. 31) is not within tolerance move the passive end frame by -gain * dP_Bp with
/// dP_Bp = R_BpC (du z / fx, dv z / fy, 0) (eq. 42-43), keeping its nominal orientation, via
/// nominal IK seeded at the encoders. Never loops past max_iterations moves. Throws InputError
/// for bad options or setup (robot index, board); cell failures come back as a status.
ServoResult AlignFeatureToOpticalAxis(Cell& cell, const ServoSetup& setup,
                                      const JointVector& q_passive_start,
                                      const ServoOptions& options = {});

}  // namespace twin
