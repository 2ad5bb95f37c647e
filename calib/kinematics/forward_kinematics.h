// Forward kinematics (Zhu et al. 2019, eq. 1), the manipulator Jacobian, and the analytic
// identification Jacobian of the tool pose with respect to all 35 link parameters (eq. 5-9).
#pragma once

#include <array>

#include <Eigen/Core>

#include "calib/kinematics/kinematic_model.h"
#include "calib/model/parameters.h"

namespace twin {

/// Poses of every frame of one arm in its base frame B at joint angles q.
struct FrameSet {
  std::array<Transform, kNumLinks + 1> X_BL;  ///< X_BL[i] is DH frame Li, i = 0..7
  Transform X_BE;                             ///< end frame (X_BL[7] * X_L7E)
  const Transform& flange() const { return X_BL[kNumJoints]; }
};

/// Eq. 1: poses of L0..L7 and E in B.
FrameSet ForwardKinematics(const KinematicModel& model, const JointVector& q);

/// Pose of the end frame E in B (the tool: feature point or camera mount).
Transform EndPose(const KinematicModel& model, const JointVector& q);

/// 6x6 geometric Jacobian of the end frame: rows 0-2 map qdot to the velocity of E's origin,
/// rows 3-5 to its angular velocity, both expressed in B [m/rad, rad/rad].
Eigen::Matrix<double, 6, kNumJoints> ManipulatorJacobian(const KinematicModel& model,
                                                         const JointVector& q);

/// Singular values of ManipulatorJacobian, descending. The smallest one is the singularity
/// measure of constraint C2 (Zhu et al. 2019, section IV).
Eigen::Matrix<double, kNumJoints, 1> JacobianSingularValues(const KinematicModel& model,
                                                            const JointVector& q);

/// Identification Jacobian (eq. 5-9, expressed in B as in eq. 10-12): rows 0-2 are
/// d p_BE / d phi [m per unit parameter], rows 3-5 the small rotation w_B of E per unit
/// parameter, such that R_BE(phi + dphi) ~ (I + [w_B x]) R_BE(phi). Columns follow the flat
/// order of parameters.h. Rotating rows 0-2 by R_BE^T gives the paper's EE-frame J_P.
Eigen::Matrix<double, 6, kNumParams> IdentificationJacobian(const KinematicModel& model,
                                                            const JointVector& q);

}  // namespace twin
