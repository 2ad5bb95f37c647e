// The handclasp base-frame calibration procedure of Gan, Dai, Dong 2014 (section 3), run through
// the Cell interface only: robot 1 (index 0) goes to each taught point, the operator jogs
// robot 2's (index 1) measuring tip onto robot 1's tip, both controllers report their tip
// positions in their own base frames from their *pendant* kinematics (the controller's model
// with the tip as tool), and CalibrateBaseFrame (calib/identification/base_calibration.h) turns the point
// pairs into X_B1B2, general and installation-constrained.
//
// Tip convention (shared by the planner, the operator of the twin and the coupled-motion check):
// the tip point is the origin of frame Tip and the tip points along +z_Tip; at a handclasp the
// two tips face each other, z_Tip2 = -z_Tip1, approaching along that common axis.
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "calib/identification/base_calibration.h"
#include "calib/cell/cell.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/identification/tip_refinement.h"

namespace twin {

/// The arm model whose end frame E is the measuring tip: the flange model's tool link (link 7)
/// is replaced by identity and X_LtE by X_FTip (flange F = DH frame L6).
KinematicModel WithTipTool(const KinematicModel& flange_model, const Transform& X_FTip);

/// Rotation of a tip that faces a tip with rotation R_A_TipOther (both in frame A): z flipped,
/// then turned by `roll` [rad] about its own z: R_A_TipOther RotX(pi) RotZ(roll).
Matrix3 FacingTipRotation(const Matrix3& R_A_TipOther, double roll);

/// Options of the taught-point planner (the operator's choice of handclasp points).
struct TeachOptions {
  /// Cube sides tried, largest first [m]; the contacts are the cube's 8 corners, so that any
  /// 4 of them not in one face form a triangular pyramid (paper section 3, Fig. 8).
  std::vector<double> cube_sides_m = {0.6, 0.5, 0.4, 0.35, 0.3, 0.25, 0.2};
  /// Accept a cube when at least this many corners are teachable (4..8).
  int min_points = 6;
  /// Lowest z of a contact in robot 1's base frame [m] (keeps the tips above the floor).
  double min_height_m = 0.15;
  /// Stand-off along the common tip axis from which robot 2 approaches [m]; it must be
  /// reachable as well.
  double standoff_m = 0.05;
  /// Roll angles about the tip axis tried per robot (evenly spaced over 360 deg).
  int rolls = 8;
  /// Random IK restarts per roll (0: only the seed).
  int ik_restarts = 2;
  /// Seed of the IK restarts.
  std::uint64_t seed = 1;
  /// Robot 1 tip orientations taught per point (1..8): the first points at robot 2's shoulder,
  /// the others are that direction tilted by tilt_deg about axes spread evenly around it. More
  /// than one gives the orientation variety the tip identification needs (tip_refinement.h).
  int orientations_per_point = 1;
  /// Tilt of the extra orientations [deg] (0 < tilt < 90).
  double tilt_deg = 30.0;

  /// Throws PreconditionError naming the bad field and its value (no user sets these).
  void Validate() const;
};

/// Taught points: robot 1's joint angles at each contact and what was left out.
struct TaughtPoints {
  bool ok = false;                       ///< enough teachable points
  std::string reason;                    ///< why not, when !ok
  double cube_side_m = 0.0;              ///< planner: side of the accepted cube [m]
  std::vector<Vector3> p_B1;             ///< nominal contact points in B1 [m], one per pose
  std::vector<JointVector> q1;           ///< robot 1 joint angles (motor side) [rad]
  int points = 0;                        ///< distinct points taught (p_B1 repeats per orientation)
  std::vector<std::string> rejected;     ///< "point i: reason" for points left out
};

/// Robot 1's joint angles for the contact points p_B1 (m, in B1): robot 1's tip at the point
/// pointing at robot 2's shoulder, robot 2's facing tip (and its stand-off) reachable by IK on
/// the given tip models through the rough X_B1B2_rough. Points that fail are listed in
/// `rejected`; ok when at least options.min_points (capped at the point count) remain.
TaughtPoints TeachPoints(const std::array<KinematicModel, 2>& tip_models,
                         const Transform& X_B1B2_rough, const std::vector<Vector3>& p_B1,
                         const std::array<JointVector, 2>& q_seed,
                         const TeachOptions& options = {});

/// Plans contact points automatically: the corners of the largest cube (options.cube_sides_m)
/// centred between the two shoulders, its edges along and across the shoulder line, of which
/// at least options.min_points are teachable (TeachPoints).
TaughtPoints PlanTaughtPoints(const std::array<KinematicModel, 2>& tip_models,
                              const Transform& X_B1B2_rough,
                              const std::array<JointVector, 2>& q_seed,
                              const TeachOptions& options = {});

/// Options of the handclasp procedure.
struct HandclaspOptions {
  /// The installation refinement (base_calibration.h) besides the general solution.
  BaseConstraint constraint = BaseConstraint::kGeneral;
  /// Passed to CalibrateBaseFrame.
  BaseCalibrationOptions base;
  /// After each contact robot 2 backs off this far along its tip axis, then returns to the
  /// pose it started the procedure in [m].
  double retract_m = 0.05;
  /// IK options of the retract move (pendant model of robot 2).
  IkOptions ik;
  /// Also refine X_B1B2 jointly with both tips' positions on their flanges (tip_refinement.h;
  /// beyond the paper): for pendant models whose flange frame is known only up to a constant
  /// rotation, as after an optical-axis calibration. Needs contacts of varied orientation
  /// (TeachOptions::orientations_per_point).
  bool identify_tips = false;
  TipRefinementOptions tips;

  /// Throws PreconditionError naming the bad field and its value (no user sets these).
  void Validate() const;
};

/// One registered contact.
struct HandclaspContact {
  int point = 0;                          ///< index of the taught point
  JointVector q1;   ///< robot 1 encoders [rad]
  JointVector q2;   ///< robot 2 encoders [rad]
  Vector3 p_B1 = Vector3::Zero();         ///< robot 1's pendant tip position in B1 [m]
  Vector3 p_B2 = Vector3::Zero();         ///< robot 2's pendant tip position in B2 [m]
};

/// Outcome of RunHandclaspProcedure.
struct HandclaspResult {
  enum class Status {
    kSuccess,            ///< calibration holds both transforms
    kTooFewContacts,     ///< fewer than 4 contacts registered; nothing computed
    kCalibrationFailed,  ///< CalibrateBaseFrame refused or failed (calibration.reason)
  };
  Status status = Status::kTooFewContacts;
  std::string reason;                       ///< why not kSuccess
  std::vector<HandclaspContact> contacts;   ///< registered contacts, in teaching order
  std::vector<std::string> skipped;         ///< "point i: reason" for failed contacts
  BaseCalibrationResult calibration;        ///< general and constrained X_B1B2
  /// With options.identify_tips: X_B1B2 and the tip corrections (tips.ok false, with a reason
  /// and a warning in `calibration.warnings`, when the contacts cannot separate them).
  TipRefinementResult tips;

  bool ok() const { return status == Status::kSuccess; }
};

/// Name of a status, e.g. "kTooFewContacts".
const char* ToString(HandclaspResult::Status status);

/// Runs the procedure: for each of robot 1's taught joint angles `taught_q1` (rad) move robot 1
/// there, JogTipToContact(1), read both encoders, compute p_B1 and p_B2 with the pendant tip
/// models (WithTipTool of the controller's kinematics), retract robot 2; then calibrate. Failed
/// moves or contacts are skipped and logged to `log` (may be null). Throws PreconditionError for
/// bad options or non-finite taught angles.
HandclaspResult RunHandclaspProcedure(Cell& cell,
                                      const std::array<KinematicModel, 2>& pendant_tip_models,
                                      const std::vector<JointVector>& taught_q1,
                                      const HandclaspOptions& options, std::ostream* log);

}  // namespace twin
