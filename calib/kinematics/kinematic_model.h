// Serial-chain kinematic model in the improved DH (Hayati) form of Zhu et al. 2019, eq. 2-3.
//
// Link i (1..7) maps frame L(i-1) to frame Li by
//   X_L(i-1)Li = RotZ(theta_i) * TransZ(d_i) * TransX(a_i) * RotX(alpha_i) * RotY(beta_i),
// with theta_i = q_i + theta_offset_i for the six jointed links and theta_7 = theta_offset_7
// for the fixed tool link 7. With beta_i = 0 this is classic DH (eq. 3); beta_i is the Hayati
// angle used where adjacent joint axes are (nearly) parallel (eq. 2). Each link therefore has
// the five parameters (theta, d, a, alpha, beta) and a 6-DOF arm has 35 (the paper's count).
// Two fixed, non-identified transforms complete the chain: X_BL0 (robot base frame to DH frame
// 0, identity for models written in DH) and X_L7E (tool link frame to the end frame, identity
// unless an imported URDF's tip needs it).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/common/frames.h"

namespace twin {

constexpr int kNumJoints = 6;               ///< jointed links of one arm
constexpr int kNumLinks = kNumJoints + 1;   ///< jointed links plus the fixed tool link 7
constexpr int kParamsPerLink = 5;           ///< theta, d, a, alpha, beta
constexpr int kNumParams = kNumLinks * kParamsPerLink;  ///< 35 per arm

using JointVector = Eigen::Matrix<double, kNumJoints, 1>;  ///< joint angles q [rad]

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
  DhParameters dh;           ///< eq. 2 parameters
  JointLimits limits;        ///< unused for the tool link
  LinkInertia inertia;       ///< mass properties (tool link: the mounted tool)
};

/// An immutable arm description: free functions compute with it (Pinocchio-style model).
struct KinematicModel {
  std::string name;                                  ///< robot name, prefix of parameter names
  Transform X_BL0 = Transform::Identity();           ///< base frame to DH frame 0
  std::array<Link, kNumLinks> links;                 ///< links 1..6 jointed, [6] is tool link 7
  Transform X_L7E = Transform::Identity();           ///< tool link frame to end frame

  const Link& tool() const { return links[kNumJoints]; }
};

/// Checks the model's own consistency (finite numbers, lower < upper, mass >= 0, proper
/// rotations in the fixed transforms). Throws InputError naming `where`, the link and the field.
void ValidateModel(const KinematicModel& model, const std::string& where);

/// The transform of eq. 2 for one link at joint angle q (q = 0 for the tool link).
Transform LinkTransform(const DhParameters& dh, double q);

/// True if q is inside the model's joint limits (inclusive) for every joint.
bool WithinLimits(const KinematicModel& model, const JointVector& q);

/// Midpoint of each joint's travel [rad].
JointVector MidRange(const KinematicModel& model);

}  // namespace twin
