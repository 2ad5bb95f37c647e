// The MuJoCo twin of a robot cell: two robots with the hand camera and the board, or one robot
// alone (TwinSpec::num_robots). It implements the Cell interface (what the estimator may use)
// and, separately and explicitly, TwinCell::Truth() for scoring in bench/.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "calib/cell/cell.h"
#include "sim/effects/effect.h"
#include "sim/world/twin_spec.h"

namespace twin {

/// What only the twin knows; bench/ reads it for scoring after a procedure, never calib/.
/// Per-robot arrays hold the cell's robots in their first num_robots entries.
struct TwinTruth {
  int num_robots = kMaxRobots;                     ///< the cell's robots (TwinSpec::num_robots)
  std::array<KinematicModel, kMaxRobots> models;   ///< true geometry, effects applied; a
                                                   ///< drifting one (thermal_drift) as at
                                                   ///< time 0, the start of the session
  std::array<double, kMaxRobots> length_scale{1.0, 1.0};  ///< factor on d and a of every link
                                                   ///< of `models` now (drift; 1 without)
  double time_s = 0.0;                             ///< the twin's clock now [s]
  std::array<Transform, kMaxRobots> X_WB{Transform::Identity(), Transform::Identity()};
                                                   ///< base poses in the world (identity
                                                   ///< beyond num_robots, as X_WF, X_FTip)
  std::array<JointVector, kMaxRobots> q_link;      ///< current link-side joint angles [rad]
  std::array<JointVector, kMaxRobots> q_motor;     ///< current motor-side angles [rad]
  Transform X_WC = Transform::Identity();          ///< camera optical frame in the world now
                                                   ///< (identity without a camera)
  Transform X_WT = Transform::Identity();          ///< board frame (origin P) in the world now
                                                   ///< (identity without a board)
  std::array<Vector3, kMaxRobots> p_WTip{Vector3::Zero(), Vector3::Zero()};
                                                   ///< measuring tip points in the world now
  std::array<Transform, kMaxRobots> X_WF{Transform::Identity(), Transform::Identity()};
                                                   ///< flange frames in the world now (physics:
                                                   ///< every effect included)
  std::array<Transform, kMaxRobots> X_FTip{Transform::Identity(), Transform::Identity()};
                                                   ///< the measuring tips in their flange
                                                   ///< frames, as made (TwinSpec::tips)
  CameraSpec camera;                               ///< true intrinsics, distortion, hand-eye
  BoardSpec board;                                 ///< true board geometry and mount (both
                                                   ///< unused without camera and board)
  TrackerSpec tracker;                             ///< true tracker pose, reflector, noise
};

class TwinCell : public Cell {
 public:
  /// Validates `spec`, applies geometry effects, builds the MJCF and the MuJoCo model, places
  /// the robots at their initial angles and lets them settle. Throws InputError for bad spec
  /// values (naming `where`) and for initial poses that collide or leave the limits. A robot
  /// index outside the cell's robots is kInvalidInput (MoveTo) or an InputError.
  explicit TwinCell(const TwinSpec& spec, const std::string& where = "scenario");
  ~TwinCell() override;

  MoveResult MoveTo(int robot, const JointVector& q_target) override;
  JointVector ReadEncoders(int robot) override;
  /// Throws InputError naming `where` on a cell without a hand camera (one robot), as do
  /// GrabImageRegion, CameraRobot and RenderBare.
  cv::Mat GrabImage() override;
  /// Renders only the region (OffscreenRenderer::RenderPinholeRegion; with distortion the
  /// canvas region it samples, DistortionMapper::CanvasRegion), then the image effects.
  cv::Mat GrabImageRegion(const cv::Rect& roi) override;
  /// kInvalidInput on a cell without camera and board.
  MoveResult ExchangeTools() override;
  int CameraRobot() override;
  /// Swaps the plate on the board's bracket (TwinSpec::intrinsics_target) and rebuilds the
  /// world with the robots where they stand, as ExchangeTools does; Truth().board is then the
  /// mounted plate. kInvalidInput when the spec has no intrinsics target (or, one robot, no
  /// board); kCollision (nothing changed) when the other plate would touch something.
  MoveResult MountTarget(BracketTarget target) override;
  /// The simulated operator's handclasp (Gan et al. 2014, section 3): using the true
  /// kinematics (a person looking at the tips), robot `jogged_robot` is driven by settled moves
  /// to a stand-off in front of the other tip, then along the common tip axis, then by small
  /// corrective jogs, until its true tip point is within kContactToleranceM of the other true
  /// tip point plus the operator's alignment error (drawn per contact, N(0, sigma) per world
  /// axis). Tips do not collide with each other in the MJCF, so contact is decided from the
  /// MuJoCo site positions. kInvalidInput on a one-robot cell.
  MoveResult JogTipToContact(int jogged_robot) override;
  /// The tracker of the spec (TrackerSpec): the reflector's true position from MuJoCo's flange
  /// frame (sag included), out of range beyond max_range, occluded when a ray from the tracker
  /// hits a geom before the reflector (the reflector's own flange body excepted), else the
  /// position in the tracker frame with its noise and drift.
  TrackerReading MeasureTracker(int robot) override;
  /// The twin's simulated time [s] (TwinTruth::time_s).
  double ClockSeconds() override;
  double ReadTemperatureC(int robot) override;

  /// Standard deviation of the operator's alignment error per world axis [m] (default 0).
  /// Throws InputError for a negative or non-finite value.
  void SetOperatorAlignmentError(double sigma_m);
  /// Distance between the jogged tip and the operator's aim point after the last successful
  /// JogTipToContact [m] (tests: the settling floor of the contact).
  double last_contact_gap_m() const;
  /// Contact is confirmed when the jogged tip is this close to the aim point [m]: about the
  /// servo settling floor (measured ~1e-11 m: settled below 1e-6 rad/s for 20 steps).
  static constexpr double kContactToleranceM = 1e-9;

  /// Ground truth for scoring (bench/ only).
  TwinTruth Truth() const;
  /// The generated MJCF text (for inspection and tests).
  const std::string& mjcf() const;
  /// A third-person view of the whole cell, width x height, from `azimuth`/`elevation` [deg].
  cv::Mat RenderOverview(int width, int height, double azimuth_deg, double elevation_deg);
  /// Poses in the world of MuJoCo's sites for DH frames L0..Lt of robot `robot` (tests).
  std::vector<Transform> SiteFrames(int robot) const;
  /// Steps taken by the last MoveTo (benchmarks).
  int last_move_steps() const;
  /// The benchmark baseline: bare mjr_render + mjr_readPixels of the hand camera.
  void RenderBare();

  /// Stops a MoveTo in progress, from any thread (a served cell's watchdog): the move ends at
  /// its next physics step with kNotSettled, reason "stopped", the robot holding where it
  /// stands (a handclasp or a tool exchange likewise ends its settling). The request clears
  /// when the next MoveTo, JogTipToContact, ExchangeTools or MountTarget starts (a request while
  /// no motion runs stops nothing).
  void RequestStop();
  /// Paces the simulation to wall-clock time (a served twin behaving like hardware): each
  /// physics step of a move waits until its simulated time has passed in wall time. Off by
  /// default (the simulation runs as fast as it can; results are the same either way).
  void SetRealtime(bool realtime);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  MoveResult RemountTools(const std::function<void()>& change, const std::string& what,
                          const std::string& refused);
};

}  // namespace twin
