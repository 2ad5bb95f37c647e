// Forward kinematics (Zhu et al. 2019, eq. 1-2), the manipulator Jacobian, and the analytic
// identification Jacobian of the tool pose with respect to the 5 (N + 1) link parameters
// (eq. 5-9).
//
// There is one forward kinematics: ChainFramesT, templated on the scalar, so that double
// callers (IK, the planner, scoring) and the Ceres solvers (ceres::Jet) run the same code. The
// double functions below call it. The analytic IdentificationJacobian is kept because the pose
// planner evaluates it for every candidate pose set (tests hold it against autodiff of
// ChainFramesT; bench: `twinbench benchmark-kinematics` prints the speed-up).
#pragma once

#include <array>

#include <Eigen/Core>

#include "calib/kinematics/kinematic_model.h"
#include "calib/kinematics/rigid_transform.h"
#include "calib/model/parameters.h"

namespace twin {

/// Eq. 2 on scalar T: X_L(i-1)Li = RotZ(dh[0] + q) TransZ(dh[1]) TransX(dh[2]) RotX(dh[3])
/// RotY(dh[4]), with dh = (theta_offset, d, a, alpha, beta) [rad, m, m, rad, rad] and q the
/// link-side joint angle [rad]; `length_scale` multiplies d and a (1 for the geometric model;
/// thermal terms change it).
/// cos and sin of a link's constant angles alpha (dh[3]) and beta (dh[4]).
template <typename T>
struct LinkTrigT {
  T ca, sa, cb, sb;
};

/// Eq. 2 with the link's alpha and beta given by their cosines and sines (computed once by a
/// caller that evaluates one model many times); the formula of the overload below.
template <typename T>
RigidT<T> LinkTransformT(const T* dh, const T& q, const T& length_scale,
                         const LinkTrigT<T>& trig) {
  using std::cos;
  using std::sin;
  const T th = dh[0] + q;
  const T ct = cos(th), st = sin(th);
  const T &ca = trig.ca, &sa = trig.sa, &cb = trig.cb, &sb = trig.sb;
  RigidT<T> X;
  X.R << ct * cb - st * sa * sb, -st * ca, ct * sb + st * sa * cb,
         st * cb + ct * sa * sb, ct * ca, st * sb - ct * sa * cb,
         -ca * sb, sa, ca * cb;
  const T a = dh[2] * length_scale;
  X.p << a * ct, a * st, dh[1] * length_scale;
  return X;
}

template <typename T>
RigidT<T> LinkTransformT(const T* dh, const T& q, const T& length_scale) {
  using std::cos;
  using std::sin;
  return LinkTransformT(dh, q, length_scale,
                        LinkTrigT<T>{cos(dh[3]), sin(dh[3]), cos(dh[4]), sin(dh[4])});
}

/// Eq. 1 on scalar T: the poses X_BL[0..N+1] of DH frames L0..Lt in the base frame B, for the
/// geometric parameters `phi` (5 (N + 1) values, flat order of parameters.h), link-side joint
/// angles `q_link` (N values) and a length scale applied to every d and a. X_BL must hold
/// model.num_links() + 1 entries. `trig` (optional, num_links() entries): the links' alpha and
/// beta cosines and sines of these phi, precomputed (the same numbers, bit for bit).
template <typename T>
void ChainFramesT(const KinematicModel& model, const T* phi, const T* q_link,
                  const T& length_scale, RigidT<T>* X_BL, const LinkTrigT<T>* trig = nullptr) {
  const int n = model.num_joints();
  X_BL[0] = RigidT<T>::FromTransform(model.X_BL0);
  for (int i = 0; i <= n; ++i) {
    const T q = i < n ? q_link[i] : T(0.0);
    const T* dh = phi + kParamsPerLink * i;
    X_BL[i + 1] = X_BL[i] * (trig ? LinkTransformT(dh, q, length_scale, trig[i])
                                  : LinkTransformT(dh, q, length_scale));
  }
}

/// Pose X_BE of the end frame on scalar T (same inputs as ChainFramesT).
template <typename T>
RigidT<T> ChainEndPoseT(const KinematicModel& model, const T* phi, const T* q_link,
                        const T& length_scale, const LinkTrigT<T>* trig = nullptr) {
  const int n = model.num_joints();
  RigidT<T> X = RigidT<T>::FromTransform(model.X_BL0);
  for (int i = 0; i <= n; ++i) {
    const T q = i < n ? q_link[i] : T(0.0);
    const T* dh = phi + kParamsPerLink * i;
    X = X * (trig ? LinkTransformT(dh, q, length_scale, trig[i])
                  : LinkTransformT(dh, q, length_scale));
  }
  return X * RigidT<T>::FromTransform(model.X_LtE);
}

/// Poses of every frame of one arm in its base frame B at joint angles q.
struct FrameSet {
  int num_joints = 0;                          ///< N
  std::array<Transform, kMaxJoints + 2> X_BL;  ///< X_BL[i] is DH frame Li, i = 0..N+1
  Transform X_BE = Transform::Identity();      ///< end frame (X_BL[N+1] * X_LtE)
  const Transform& flange() const { return X_BL[num_joints]; }
  const Transform& tool() const { return X_BL[num_joints + 1]; }
};

/// The cosines and sines of every link's alpha and beta of one model, for repeated forward
/// kinematics of that model at many joint angles (IK's iterations, the planner's checks): the
/// functions below give bit-equal results with or without it, faster with it.
struct ChainTrig {
  ChainTrig() = default;  ///< empty: assign ChainTrig(model) before use
  explicit ChainTrig(const KinematicModel& model);
  std::array<LinkTrigT<double>, kMaxJoints + 1> link{};
};

/// Eq. 1: poses of L0..Lt and E in B (ChainFramesT in double); `trig` of this model or null.
FrameSet ForwardKinematics(const KinematicModel& model, const JointVector& q,
                           const ChainTrig* trig = nullptr);

/// Pose of the end frame E in B (the tool: feature point or camera mount).
Transform EndPose(const KinematicModel& model, const JointVector& q,
                  const ChainTrig* trig = nullptr);

/// ForwardKinematics and EndPose from one pass over the chain (IK needs both at every
/// iterate): fills `frames` as ForwardKinematics gives them and returns EndPose, each bit for
/// bit (the chain's products are the same operations in the same order).
Transform FramesAndEndPose(const KinematicModel& model, const JointVector& q,
                           const ChainTrig* trig, FrameSet* frames);

/// 6 x N matrix with inline storage (Jacobians with respect to joint angles).
using JointJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxJoints>;

/// ManipulatorJacobian from frames ForwardKinematics (or FramesAndEndPose) computed.
JointJacobian ManipulatorJacobian(const FrameSet& frames);

/// 6xN geometric Jacobian of the end frame: rows 0-2 map qdot to the velocity of E's origin,
/// rows 3-5 to its angular velocity, both expressed in B [m/rad, rad/rad].
JointJacobian ManipulatorJacobian(const KinematicModel& model, const JointVector& q,
                                  const ChainTrig* trig = nullptr);

/// Singular values of ManipulatorJacobian, descending (min(6, N) of them). The smallest one is
/// the singularity measure of constraint C2 (Zhu et al. 2019, section IV).
Eigen::VectorXd JacobianSingularValues(const KinematicModel& model, const JointVector& q,
                                       const ChainTrig* trig = nullptr);

/// The smallest of JacobianSingularValues.
double SmallestJacobianSingularValue(const KinematicModel& model, const JointVector& q,
                                     const ChainTrig* trig = nullptr);

/// 6 x 5 (N + 1) matrix with inline storage (Jacobians with respect to link parameters).
using ParameterJacobian =
    Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kParamsPerLink * (kMaxJoints + 1)>;

/// Identification Jacobian (eq. 5-9, expressed in B as in eq. 10-12): rows 0-2 are
/// d p_BE / d phi [m per unit parameter], rows 3-5 the small rotation w_B of E per unit
/// parameter, such that R_BE(phi + dphi) ~ (I + [w_B x]) R_BE(phi). Columns follow the flat
/// order of parameters.h. Rotating rows 0-2 by R_BE^T gives the paper's EE-frame J_P.
ParameterJacobian IdentificationJacobian(const KinematicModel& model, const JointVector& q);

/// The columns of IdentificationJacobian from the frames X_BL (L0..Lt in B) of a chain of
/// `num_links` links with geometric parameters `phi` (for the Hayati angles), the end point
/// p_BE, and a length scale s that multiplies every d and a (so their columns are s times the
/// unit-scale ones). Shared by IdentificationJacobian and the robot model's end-point Jacobian.
void IdentificationColumns(int num_links, const RigidT<double>* X_BL, const double* phi,
                           const Vector3& p_BE, double length_scale, ParameterJacobian* J);

}  // namespace twin
