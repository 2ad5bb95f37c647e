// Intrinsic calibration of the hand camera by Zhang's method (Z. Zhang, "A Flexible New
// Technique for Camera Calibration", IEEE TPAMI 22(11), 2000), as OpenCV's calibrateCamera
// implements it: homographies of the planar board (z = 0) in several tilted views give a
// closed-form start, then Levenberg-Marquardt refines intrinsics, distortion and view poses.
// Zhu et al. 2019, section VI.A, calibrate the camera this way before the robot calibration;
// the result feeds PinholeIntrinsics of the visual servo. Talks to the cell only through Cell.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "calib/cell/cell.h"
#include "calib/vision/feature_detector.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/vision/visual_servo.h"

namespace twin {

/// Options of CalibrateIntrinsics.
struct IntrinsicsOptions {
  int min_views = 10;               ///< views with a detected board needed to calibrate (>= 3)
  bool fix_k3 = true;               ///< hold k3 at 0 (a small board cannot constrain it)
  bool fix_all_distortion = false;  ///< hold k1, k2, p1, p2, k3 at 0 (pure pinhole)
  /// Drop views whose reprojection RMS exceeds this many times the median view's, worst first,
  /// recalibrating after each, while more than min_views remain (0: keep every view; else > 1).
  double max_view_error_ratio = 3.0;
};

/// Throws PreconditionError naming the bad field and value (no user input sets these options).
void ValidateIntrinsicsOptions(const IntrinsicsOptions& options);

enum class IntrinsicsStatus {
  kSuccess,       ///< calibrated from at least min_views views
  kTooFewViews,   ///< fewer than min_views views with a detected board (reason says how many)
  kFailed,        ///< OpenCV failed or returned non-finite values (reason says why)
};

/// Name of a status for messages ("success", "too_few_views", "failed").
const char* ToString(IntrinsicsStatus status);

/// Brown-Conrady distortion in OpenCV's order (k1, k2, p1, p2, k3) [-].
struct DistortionCoefficients {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
};

/// Outcome of CalibrateIntrinsics; intrinsics and distortion are meaningful only on kSuccess.
struct IntrinsicsResult {
  IntrinsicsStatus status = IntrinsicsStatus::kFailed;
  std::string reason;                  ///< cause when not successful, empty on success
  PinholeIntrinsics intrinsics;        ///< estimated fx, fy, cx, cy [px]
  DistortionCoefficients distortion;   ///< estimated distortion [-]
  double rms_px = 0;                   ///< RMS reprojection error over all corners [px]
  int views_used = 0;                  ///< views whose corners entered the calibration
  /// One line per skipped pose (failed move, no board, dropped as an outlier view).
  std::vector<std::string> skipped;
  double detect_s = 0;     ///< wall time in corner detection, every view [s]
  double calibrate_s = 0;  ///< wall time in cv::calibrateCamera, every round [s]
};

/// Moves robot `board_robot` to each of `board_poses` (motor angles [rad]), grabs an image,
/// detects all inner corners with DetectFeaturePoint and runs cv::calibrateCamera with the
/// board's object points on its plane z = 0 [m]. Failed moves and images without the board are
/// skipped and logged in `skipped`. Throws PreconditionError for bad options, board or robot
/// index.
IntrinsicsResult CalibrateIntrinsics(Cell& cell, int board_robot,
                                     const std::vector<JointVector>& board_poses,
                                     const BoardGeometry& board,
                                     const IntrinsicsOptions& options = {});

/// The calibration step of CalibrateIntrinsics on detected corners: per view its object points
/// (board plane, z = 0 [m]), image points [px] and the index of the pose it was taken at (for
/// the messages); `poses` is how many poses were tried, `result` carries the skipped lines so
/// far. Zhang's method (cv::calibrateCamera), then outlier views dropped as max_view_error_ratio
/// says, each with a line in `skipped`. Throws PreconditionError for bad options, unequal counts
/// or an empty image size; a view set cv::calibrateCamera refuses gives kFailed.
IntrinsicsResult CalibrateFromCorners(std::vector<std::vector<cv::Point3f>> object_points,
                                      std::vector<std::vector<cv::Point2f>> image_points,
                                      std::vector<int> view_pose, cv::Size image_size,
                                      int poses, const IntrinsicsOptions& options,
                                      IntrinsicsResult result = {});

/// n poses for intrinsic calibration around q_center (a pose where the camera sees the board):
/// the first is q_center, the others perturb joints 4-6 uniformly within +-20 deg and joints
/// 1-3 within +-5 deg so the board appears tilted and shifted; all inside the model's limits.
/// Reproducible for a given seed. Throws PreconditionError for n < 1, InputError for q_center
/// outside the limits or too close to them (the scenario's start pose).
std::vector<JointVector> IntrinsicsViewPoses(const KinematicModel& board_model,
                                             const JointVector& q_center, int n,
                                             std::uint64_t seed);

/// Where PlannedIntrinsicsViews puts the board, relative to the camera.
struct IntrinsicsViewSpec {
  double min_depth_m = 0.20;                 ///< nearest board centre along the axis [m]
  double max_depth_m = 0.40;                 ///< farthest [m]
  double half_angle_x = DegToRad(17.0);      ///< board centre off-axis, horizontally [rad]
  double half_angle_y = DegToRad(12.0);      ///< ... vertically (inside a ~60 x 50 deg view)
  /// Board normal away from the line of sight [rad]. Zhang's method gets the focal length
  /// from perspective foreshortening, so near, strongly tilted views pin it best: simulated
  /// 3 x 3 corner views with 0.035 px noise give an fx error of 0.32 % RMS for 25 views tilted
  /// 15-40 deg at 0.28-0.55 m, 0.09 % for 40 views tilted 30-55 deg at 0.2-0.4 m.
  double min_tilt = DegToRad(30.0);
  double max_tilt = DegToRad(55.0);          ///< [rad]
};

/// The default view spec for a plate of this size, s its larger printed side: the defaults
/// above (made for the 4 x 4 board of 20 mm squares) for s up to 0.16 m; for a larger target
/// depths [1.43 s, 2.14 s] (never nearer than the defaults), board centres within
/// 0.16 / s of the default directions (so the target stays in view), tilts 40-60 deg. For a
/// 14 x 10 target of 20 mm squares (0.28 m): 0.4-0.6 m, +-9.7 x 6.9 deg. On the twin, 40 such
/// views gave fx within 1.5e-4 of the truth over 41 paper-scenario trials, the 4 x 4 board's
/// 40 views within 1.7e-3 (README.md of e5af83d, "Figures on the paper scenario").
IntrinsicsViewSpec IntrinsicsViewSpecFor(const BoardGeometry& plate);

/// n board poses designed in the camera frame for Zhang's method: board centres spread over
/// the field of view (a jittered grid of directions) at depths over [min, max], each board
/// tilted by min..max_tilt about a random in-plane axis and turned randomly about its normal;
/// joint angles of the board robot from nominal IK (seeded at q_seed). X_BbC is the camera in
/// the board robot's base, from rough knowledge: poses need not be accurate, only well spread.
/// Poses whose IK fails or leaves the limits are replaced by new draws. Reproducible per seed.
/// Throws PreconditionError for n < 1, InputError when fewer than n poses are found in 50 n
/// draws (the scenario's cell leaves the board no room in front of the camera).
std::vector<JointVector> PlannedIntrinsicsViews(const KinematicModel& board_model,
                                                const JointVector& q_seed,
                                                const Transform& X_BbC, int n, std::uint64_t seed,
                                                const IntrinsicsViewSpec& spec = {});

}  // namespace twin
