// Serial-chain kinematic model in the improved DH (Hayati) form of Zhu et al. 2019, eq. 2-3,
// for a chain of N revolute joints (N is a run-time property: 6 for the paper's arms, 7 for a
// redundant arm, at most kMaxJoints).
//
// Link i (1..N+1) maps frame L(i-1) to frame Li by
//   X_L(i-1)Li = RotZ(theta_i) * TransZ(d_i) * TransX(a_i) * RotX(alpha_i) * RotY(beta_i),
// with theta_i = q_i + theta_offset_i for the N jointed links and theta_t = theta_offset_t for
// the fixed tool link t = N+1 (link 7 of a six-axis arm). With beta_i = 0 this is classic DH
// (eq. 3); beta_i is the Hayati angle used where adjacent joint axes are (nearly) parallel
// (eq. 2). Each link has the five parameters (theta, d, a, alpha, beta), so a 6-DOF arm has 35
// (the paper's count) and an N-joint arm 5 (N + 1). Two fixed, non-identified transforms
// complete the chain: X_BL0 (robot base frame to DH frame 0, identity for models written in DH)
// and X_LtE (tool link frame to the end frame, identity unless an imported URDF's tip or a
// mount's rotation needs it).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/common/frames.h"

namespace twin {

constexpr int kMaxJoints = 12;      ///< largest chain the library takes (storage bound only)
constexpr int kParamsPerLink = 5;   ///< theta, d, a, alpha, beta
constexpr int kDefaultJoints = 6;   ///< the industrial six-axis arm of both papers

/// Joint angles q of one arm [rad], one entry per joint. Dynamic size with inline storage for
/// up to kMaxJoints (no heap allocation in the kinematics' inner loops).
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;

/// The five geometric parameters of one link (eq. 2). Lengths in m, angles in rad.
struct DhParameters {
  double theta_offset = 0.0;  ///< joint angle at q = 0 [rad]
  double d = 0.0;             ///< offset along z of L(i-1) [m]
  double a = 0.0;             ///< length along the rotated x axis [m]
  double alpha = 0.0;         ///< twist about x [rad]
  double beta = 0.0;          ///< Hayati rotation about y, for parallel axes [rad]
};

/// Which of the five parameters (the flat-vector order within a link).
enum class DhParameter { kTheta = 0, kD = 1, kA = 2, kAlpha = 3, kBeta = 4 };

/// Joint travel of the motor-side (encoder) angle q [rad].
struct JointLimits {
  double lower = -kPi;  ///< [rad]
  double upper = kPi;   ///< [rad]
};

/// Rigid-body inertia of a link, expressed in the link's DH frame Li.
struct LinkInertia {
  double mass = 0.0;                              ///< [kg]
  Vector3 p_LiCom = Vector3::Zero();              ///< centre of mass in Li [m]
  Matrix3 I_Com = Matrix3::Zero();                ///< inertia about the COM, axes of Li [kg m^2]
};

/// One link: geometry, and for jointed links limits and inertia.
struct Link {
  std::string name;          ///< e.g. "link3" (used in parameter names)
  std::string joint_name;    ///< the source's name of the joint (URDF), empty when none
  DhParameters dh;           ///< eq. 2 parameters
  JointLimits limits;        ///< unused for the tool link
  LinkInertia inertia;       ///< mass properties (tool link: the mounted tool)
};

/// An immutable arm description: free functions compute with it (Pinocchio-style model).
struct KinematicModel {
  /// A chain of `num_joints` jointed links plus the tool link, all parameters zero, limits
  /// [-pi, pi], links named link1..linkN and "tool".
  explicit KinematicModel(int num_joints);
  /// A six-axis chain (kDefaultJoints), as above.
  KinematicModel() : KinematicModel(kDefaultJoints) {}

  std::string name;                         ///< robot name, prefix of parameter names
  Transform X_BL0 = Transform::Identity();  ///< base frame to DH frame 0
  std::vector<Link> links;                  ///< links 1..N jointed, links.back() the tool link
  Transform X_LtE = Transform::Identity();  ///< tool link frame to end frame

  int num_joints() const { return static_cast<int>(links.size()) - 1; }
  int num_links() const { return static_cast<int>(links.size()); }  ///< N + 1
  /// Number of geometric parameters, 5 (N + 1) [-].
  int num_parameters() const { return kParamsPerLink * num_links(); }
  const Link& tool() const { return links.back(); }
  Link& tool() { return links.back(); }
  /// The flange link N (frame L_N, where tools are mounted).
  const Link& flange() const { return links[links.size() - 2]; }
};

/// Checks the model's own consistency (1..kMaxJoints joints, finite numbers, lower < upper,
/// mass >= 0, proper rotations in the fixed transforms). Throws InputError naming `where`, the
/// link and the field.
void ValidateModel(const KinematicModel& model, const std::string& where);

/// The transform of eq. 2 for one link at joint angle q (q = 0 for the tool link).
Transform LinkTransform(const DhParameters& dh, double q);

/// Zero joint angles of the right size for `model`.
JointVector ZeroJoints(const KinematicModel& model);

/// True if q is inside the model's joint limits (inclusive) for every joint.
bool WithinLimits(const KinematicModel& model, const JointVector& q);

/// Midpoint of each joint's travel [rad].
JointVector MidRange(const KinematicModel& model);

/// q with each joint turned by whole turns (the same pose) to the angle within its limits
/// nearest ref's (unchanged where no such angle is nearer): on joints that turn more than a full
/// turn (a UR's +-360 deg) an IK solution may lie a turn away from where the arm is.
JointVector NearestTurns(const KinematicModel& model, JointVector q, const JointVector& ref);

}  // namespace twin
