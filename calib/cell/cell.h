// The Cell interface: everything the calibration procedure may ask of a robot cell, exactly
// what a hardware cell offers. sim/ implements it with the MuJoCo twin; a hardware driver
// would implement it with the robot controllers and the camera. Nothing of the truth crosses
// it (DESIGN.md: the estimator never sees the truth).
#pragma once

#include <limits>
#include <string>

#include <opencv2/core.hpp>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

enum class MoveStatus {
  kSettled,       ///< reached the targets and came to rest
  kCollision,     ///< stopped: a link, tool or the other robot was hit (reason names them)
  kNotSettled,    ///< still moving after the step limit
  kOutOfLimits,   ///< the targets are outside the joint limits; nothing moved
  kInvalidInput,  ///< unknown robot index or non-finite targets; nothing moved
};

/// Name of a status for messages ("settled", "collision", ...).
const char* ToString(MoveStatus status);

/// Outcome of Cell::MoveTo.
struct MoveResult {
  MoveStatus status = MoveStatus::kSettled;
  std::string reason;      ///< what went wrong, empty when settled
  double duration_s = 0;   ///< motion time of the move (simulated time on the twin) [s]
};

/// Outcome of Cell::MeasureTracker.
enum class TrackerStatus {
  kOk,          ///< the reflector was measured
  kNoTracker,   ///< the cell has no laser tracker, or none on this robot
  kOutOfRange,  ///< the reflector is beyond the tracker's range
  kOccluded,    ///< something stands between the tracker and the reflector (reason names it)
};

/// Name of a status for messages ("ok", "no_tracker", "out_of_range", "occluded").
const char* ToString(TrackerStatus status);

/// One laser-tracker reading of the reflector on a robot's flange, in the tracker's frame.
struct TrackerReading {
  TrackerStatus status = TrackerStatus::kNoTracker;
  std::string reason;              ///< what went wrong, empty when kOk
  Vector3 p_T = Vector3::Zero();   ///< the reflector's measured position [m]
  double time_s = 0;               ///< when it was measured (the cell's clock) [s]
};

/// What the board robot's bracket holds.
enum class BracketTarget {
  kFeatureBoard,      ///< the small calibration board whose centre corner is the feature point
  kIntrinsicsTarget,  ///< a larger chessboard for the camera's intrinsic calibration only
};

/// Name of a target for messages ("feature_board", "intrinsics_target").
const char* ToString(BracketTarget target);

/// A cell with two robots (indices 0 and 1) and one hand camera, or with one robot (index 0)
/// and no camera (a laser-tracker cell): there the camera's methods (GrabImage, CameraRobot,
/// ExchangeTools) refuse, and a procedure that needs them cannot run.
class Cell {
 public:
  virtual ~Cell() = default;
  /// Moves robot `robot` to motor-side joint targets [rad] and waits until it has settled.
  virtual MoveResult MoveTo(int robot, const JointVector& q_target) = 0;
  /// Joint encoder reading of robot `robot` (motor side, as the controller reports it) [rad].
  virtual JointVector ReadEncoders(int robot) = 0;
  /// One frame of the hand camera: 8-bit BGR, OpenCV row order (row 0 at the top).
  virtual cv::Mat GrabImage() = 0;
  /// The pixels `roi` of the next frame, clipped to the image: an image of the clipped size
  /// whose pixel (0, 0) is frame pixel roi.tl(); nothing outside it is seen. A cell that can
  /// render or read out a region faster overrides this (the twin renders only the region);
  /// the default grabs a whole frame and crops it. An empty result: roi misses the image.
  virtual cv::Mat GrabImageRegion(const cv::Rect& roi);
  /// Exchanges the hand camera and the chessboard between the two flanges, each onto the
  /// other's bracket (Zhu et al. 2019, section II: "the roles of the passive and active robots
  /// are exchanged"); the robots hold still. On a hardware cell the operator does it and
  /// confirms. Fails (status and reason, nothing changed) when the tools cannot be exchanged
  /// where the robots stand.
  virtual MoveResult ExchangeTools() = 0;
  /// Index of the robot that carries the hand camera now; the other carries the board.
  virtual int CameraRobot() = 0;
  /// Asks the operator to jog robot `jogged_robot`'s measuring tip onto the other robot's tip
  /// and to confirm the contact (the "handclasp" of Gan et al. 2014, section 3); the other robot
  /// holds still, and the jogged robot stays at the contact. Fails with a status and a reason
  /// (kInvalidInput: bad index or no handclasp on this cell; kOutOfLimits: the other tip is out
  /// of reach; kCollision; kNotSettled: the tips could not be brought together). The default
  /// is a cell without measuring tips.
  virtual MoveResult JogTipToContact(int jogged_robot) {
    MoveResult result;
    result.status = MoveStatus::kInvalidInput;
    result.reason = "this cell has no handclasp (robot " + std::to_string(jogged_robot) +
                    " cannot be jogged onto the other tip)";
    return result;
  }
  /// Asks the operator to mount `target` on the board robot's bracket, in place of what it
  /// holds (the robots hold still; on hardware the operator swaps the plates and confirms).
  /// The feature board is mounted at the start. Mounting what is already there does nothing.
  /// Fails with a status and a reason, nothing changed (kInvalidInput: the cell has no such
  /// target; kCollision: the other plate would hit something where the robots stand). The
  /// default is a cell with the feature board only.
  virtual MoveResult MountTarget(BracketTarget target) {
    MoveResult result;
    if (target != BracketTarget::kFeatureBoard) {
      result.status = MoveStatus::kInvalidInput;
      result.reason = "this cell has no intrinsics target (only the feature board)";
    }
    return result;
  }
  /// The cell's clock [s] (on hardware the controller's or the cell PC's; on the twin its
  /// simulated time), from an origin of the cell's choosing; NaN: the cell keeps no clock, the
  /// default. Time stamps of measurements (a thermal drift needs them).
  virtual double ClockSeconds() { return std::numeric_limits<double>::quiet_NaN(); }
  /// The temperature of robot `robot`'s structure as its sensor reads it now [deg C]; NaN: no
  /// sensor, the default. A thermal growth of the arm is a function of it (no extrapolation
  /// in time, as a drift over the clock needs).
  virtual double ReadTemperatureC(int robot) {
    (void)robot;
    return std::numeric_limits<double>::quiet_NaN();
  }
  /// Measures the reflector (SMR) on robot `robot`'s flange with the laser tracker, the robot
  /// standing still. The default is a cell without a tracker.
  virtual TrackerReading MeasureTracker(int robot) {
    TrackerReading r;
    r.reason = "this cell has no laser tracker (robot " + std::to_string(robot) + ")";
    return r;
  }
};

/// Robot `robot`'s temperature sensor now, less a session's reference reading [K]: the first
/// finite reading sets *reference_C (and reads 0); NaN where the cell has no sensor. What a
/// procedure records per measurement (MeasurementContext::temperature_delta_K).
double ReadTemperatureDeltaK(Cell& cell, int robot, double* reference_C);

}  // namespace twin
