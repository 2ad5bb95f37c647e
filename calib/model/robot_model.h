// The estimator's robot model (DESIGN.md): the geometric chain (N revolute joints, improved DH)
// plus zero or more error terms, with every parameter in one flat vector (ParameterLayout,
// calib/model/parameter_layout.h): the 5 (N + 1) geometric parameters first, then each term's
// in the order of `terms`.
//
// Forward kinematics of the model (RobotEndPoseT), for a measurement context c:
//   q_link   = c.q + sum of the terms' joint offsets                              (stage 1)
//   s        = product of the terms' length scales; d and a of every joint link times s,
//              not the tool link's: what the flange carries (a reflector's bracket, a
//              board) is not the arm's structure, which its drives warm        (stage 2)
//   q_link  += sum of the terms' sags c_i * tau_i(q_link), tau the gravity torques of the
//              nominal masses in the model's own geometry, solved by fixed-point iteration
//              (kSagIterations; the sag of a compliant joint changes the torques)   (stage 3)
//   X_BF     = chain to the flange L_N at q_link (eq. 1-2, ChainFramesT)
//   p_BE     = X_BF (X_FE p + dp_F), dp_F the terms' tool offsets in the flange   (stage 4)
//   where terms deflect axes (stage 5), the chain X_BF = X_BL0 prod_i Rot(w_i) X_L(i-1)Li
//              with w_i the small rotations the terms give from the frames of the chain
//              above (one pass: a deflection of 1e-4 rad changes the moments it comes from
//              by 1e-4 of themselves)
// With no terms it is exactly the geometric forward kinematics of the chain.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <ceres/rotation.h>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/model/error_term.h"
#include "calib/model/measurement_context.h"

namespace twin {

/// Standard gravity [m/s^2].
constexpr double kStandardGravity = 9.80665;

/// Fixed-point iterations of the gravity sag (stage 3), at most. The error after k iterations is
/// about (c dtau/dq)^k times the sag: with c = 1e-4 rad/(N m) (a soft joint) and dtau/dq ~ 100
/// N m/rad that is 1e-2 per iteration, so 4 iterations leave 1e-8 of a sag of ~1e-2 rad (~1e-10
/// rad). The iteration stops early once no link angle moved by more than kSagTolerance (a
/// derivative carried along converges at the same rate as the value).
constexpr int kSagIterations = 4;
constexpr double kSagTolerance = 1e-12;  ///< [rad]: a picometre a metre from the joint

/// The value of a double or of a ceres::Jet (its scalar part).
inline double ScalarPart(double x) { return x; }
template <typename Jet>
double ScalarPart(const Jet& x) {
  return x.a;
}

/// An estimator-side robot model. Immutable in use: free functions compute with it.
struct RobotModel {
  KinematicModel chain;  ///< the geometric chain (its parameters are the first block)
  std::vector<std::shared_ptr<const ErrorTerm>> terms;  ///< error terms, in layout order
  Eigen::VectorXd term_values;  ///< all term parameters, in layout order (SI)
  /// Direction of gravity in the robot's base frame (unit): (0, 0, -1) for a floor-mounted
  /// robot; what the engineer knows from the installation.
  Vector3 gravity_B = -Vector3::UnitZ();
  double gravity = kStandardGravity;  ///< magnitude [m/s^2]

  const std::string& name() const { return chain.name; }
  /// Total number of parameters (geometry plus terms).
  int num_parameters() const { return chain.num_parameters() + static_cast<int>(term_values.size()); }
};

/// A model of `chain` with no error terms.
RobotModel MakeRobotModel(const KinematicModel& chain, const Vector3& gravity_B = -Vector3::UnitZ());

/// `model` with one more term, its parameters at zero (the term's nominal: no effect). Throws
/// InputError when the same term (type, joint, orders) is already in the model (a user can
/// declare a term twice, e.g. `identify --declare`).
RobotModel WithTerm(const RobotModel& model, std::shared_ptr<const ErrorTerm> term);

/// Whether some term of `model` has dormant parameters (ErrorTerm::has_dormant_parameters)
/// while all its amplitudes are zero: there its other parameters (a warm-up's time constant)
/// have no gradient, and a fit from that start leaves them where they are.
bool HasDormantTermsAtZero(const RobotModel& model);

/// `model` with the values of each term HasDormantTermsAtZero names taken from `solved` (the
/// same terms, fitted): a start where their dormant parameters have a gradient. Precondition:
/// `solved` has the same terms (PreconditionError otherwise).
RobotModel WithDormantTermsFrom(const RobotModel& model, const RobotModel& solved);

/// The model's flat parameter vector (geometry, then the terms) [SI].
Eigen::VectorXd GetParameters(const RobotModel& model);

/// A copy of `model` with the flat parameters `params`.
RobotModel WithParameters(const RobotModel& model, const Eigen::VectorXd& params);

/// Gravity torques tau_i about each joint axis z_(i-1) [N m] of the nominal masses (each
/// link's mass at its centre of mass, the tool link's with the flange link) in the frames X_BL
/// (L0..Lt, on scalar T): tau_i = z_(i-1) . sum_(j >= i) (c_j - o_(i-1)) x (m_j g g_B). The
/// torque gravity exerts on the links beyond joint i; a joint of stiffness k sags by tau / k.
template <typename T>
void GravityTorquesT(const KinematicModel& chain, const RigidT<T>* X_BL, const Vector3& g_B,
                     double gravity, T* tau) {
  const int n = chain.num_joints();
  // Force of each link's mass and its point of application (centre of mass) in B.
  Vec3T<T> com[kMaxJoints + 1];
  for (int j = 0; j <= n; ++j) com[j] = X_BL[j + 1] * chain.links[j].inertia.p_LiCom.cast<T>();
  const Vec3T<T> g = (gravity * g_B).cast<T>();
  for (int i = 0; i < n; ++i) {
    const Vec3T<T> z = X_BL[i].R.col(2);
    const Vec3T<T>& o = X_BL[i].p;
    Vec3T<T> moment = Vec3T<T>::Zero();
    for (int j = i; j <= n; ++j) moment += (com[j] - o).cross(g * T(chain.links[j].inertia.mass));
    tau[i] = z.dot(moment);
  }
}

/// Link-side joint angles and length scale of the model for a context (stages 1-3), on
/// scalar T; `params` is the flat vector (ParameterLayout order). q_link holds N entries.
template <typename T>
void LinkAnglesT(const RobotModel& model, const T* params, const MeasurementContext& c,
                 T* q_link, T* length_scale) {
  const KinematicModel& chain = model.chain;
  const int n = chain.num_joints();
  for (int i = 0; i < n; ++i) q_link[i] = T(c.q(i));
  *length_scale = T(1.0);
  const T* p = params + chain.num_parameters();
  bool sag = false;
  for (const auto& term : model.terms) {
    term->OffsetJoints(p, c, q_link);
    term->ScaleLengths(p, c, length_scale);
    sag = sag || term->sags_under_gravity();
    p += term->parameters().size();
  }
  if (!sag) return;
  T q0[kMaxJoints];
  for (int i = 0; i < n; ++i) q0[i] = q_link[i];
  std::array<RigidT<T>, kMaxJoints + 2> X;
  T tau[kMaxJoints];
  for (int it = 0; it < kSagIterations; ++it) {
    ChainFramesT<T>(chain, params, q_link, *length_scale, X.data());
    X[n + 1] = X[n] * LinkTransformT(params + kParamsPerLink * n, T(0.0), T(1.0));  // stage 2
    GravityTorquesT<T>(chain, X.data(), model.gravity_B, model.gravity, tau);
    T before[kMaxJoints];
    for (int i = 0; i < n; ++i) {
      before[i] = q_link[i];
      q_link[i] = q0[i];
    }
    p = params + chain.num_parameters();
    for (const auto& term : model.terms) {
      term->Sag(p, tau, q_link);
      p += term->parameters().size();
    }
    double moved = 0.0;
    for (int i = 0; i < n; ++i) {
      moved = std::max(moved, std::abs(ScalarPart(q_link[i]) - ScalarPart(before[i])));
    }
    if (moved <= kSagTolerance) break;
  }
}

/// True when some term of `model` deflects axes (stage 5).
inline bool DeflectsAxes(const RobotModel& model) {
  for (const auto& term : model.terms) {
    if (term->deflects_axes()) return true;
  }
  return false;
}

/// Stage 5 of the model (header): the terms' small rotations w (3 per joint i, in the frame
/// X_BL[i] before joint i turns), given the chain's frames X (after stages 1-3, N + 2
/// entries).
template <typename T>
void AxisDeflectionsT(const RobotModel& model, const T* params, const MeasurementContext& c,
                      const RigidT<T>* X, T* w) {
  const KinematicModel& chain = model.chain;
  const int n = chain.num_joints();
  DeflectionInputT<T> in;
  in.X_BL = X;
  in.p_BE = X[n + 1] * chain.X_LtE.translation().template cast<T>();
  in.g_B = model.gravity_B;
  in.gravity = model.gravity;
  for (int k = 0; k < 3 * n; ++k) w[k] = T(0.0);
  const T* p = params + chain.num_parameters();
  for (const auto& term : model.terms) {
    if (term->deflects_axes()) term->DeflectAxes(p, c, in, w);
    p += term->parameters().size();
  }
}

/// True when the three entries at w are exactly zero, derivatives included (no term writes
/// that slot): its rotation is the identity and is skipped.
inline bool IsZeroRotation(const double* w) { return w[0] == 0.0 && w[1] == 0.0 && w[2] == 0.0; }
template <typename Jet>
bool IsZeroRotation(const Jet* w) {
  for (int k = 0; k < 3; ++k) {
    if (w[k].a != 0.0 || !w[k].v.isZero()) return false;
  }
  return true;
}

/// Rotation matrix of a small rotation vector w [rad] (Rodrigues' formula; its series near
/// zero, where a Jet's derivative needs it: ceres::AngleAxisToRotationMatrix).
template <typename T>
Mat3T<T> SmallRotationT(const T* w) {
  T R[9];
  ceres::AngleAxisToRotationMatrix(w, R);  // column-major
  Mat3T<T> M;
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) M(row, col) = R[3 * col + row];
  }
  return M;
}

/// Pose of the end frame E in B for a measurement context (the model's forward kinematics,
/// header) on scalar T. The tool offset moves E's origin only.
template <typename T>
RigidT<T> RobotEndPoseT(const RobotModel& model, const T* params, const MeasurementContext& c) {
  const KinematicModel& chain = model.chain;
  const int n = chain.num_joints();
  T q[kMaxJoints];
  T s;
  LinkAnglesT<T>(model, params, c, q, &s);
  RigidT<T> X_BF = RigidT<T>::FromTransform(chain.X_BL0);
  const RigidT<T> X_FE = LinkTransformT(params + kParamsPerLink * n, T(0.0), T(1.0)) *
                         RigidT<T>::FromTransform(chain.X_LtE);
  if (!DeflectsAxes(model)) {
    for (int i = 0; i < n; ++i) X_BF = X_BF * LinkTransformT(params + kParamsPerLink * i, q[i], s);
  } else {
    // The links' transforms once; the frames of stages 1-3 give the deflections (stage 5),
    // then the chain is composed again with them.
    std::array<RigidT<T>, kMaxJoints + 1> A;
    for (int i = 0; i < n; ++i) A[i] = LinkTransformT(params + kParamsPerLink * i, q[i], s);
    A[n] = LinkTransformT(params + kParamsPerLink * n, T(0.0), T(1.0));  // stage 2
    std::array<RigidT<T>, kMaxJoints + 2> X;
    X[0] = X_BF;
    for (int i = 0; i <= n; ++i) X[i + 1] = X[i] * A[i];
    T w[3 * kMaxJoints];
    AxisDeflectionsT<T>(model, params, c, X.data(), w);
    for (int i = 0; i < n; ++i) {
      if (!IsZeroRotation(w + 3 * i)) X_BF.R = X_BF.R * SmallRotationT<T>(w + 3 * i);
      X_BF = X_BF * A[i];
    }
  }
  Vec3T<T> dp_F = Vec3T<T>::Zero();
  const T* p = params + chain.num_parameters();
  for (const auto& term : model.terms) {
    term->OffsetTool(p, X_BF.R, model.gravity_B, &dp_F);
    p += term->parameters().size();
  }
  return {X_BF.R * X_FE.R, X_BF.p + X_BF.R * (X_FE.p + dp_F)};
}

/// RobotEndPoseT in double at the model's own parameters.
Transform EndPose(const RobotModel& model, const MeasurementContext& context);

/// Gravity torques of the model's nominal masses at link angles q [N m] (GravityTorquesT in
/// double, geometry of model.chain).
Eigen::VectorXd GravityTorques(const RobotModel& model, const JointVector& q_link);

/// Empty when every term finds what it needs in `context`, else "<term>: needs <what>".
std::string MissingContext(const RobotModel& model, const MeasurementContext& context);

}  // namespace twin
