#include "calib/kinematics/forward_kinematics.h"

#include <Eigen/SVD>

namespace twin {
namespace {

Eigen::Matrix<double, 6, 1> Twist(const Vector3& axis, const Vector3& point_on_axis,
                                  const Vector3& p) {
  Eigen::Matrix<double, 6, 1> col;
  col << axis.cross(p - point_on_axis), axis;
  return col;
}

}  // namespace

FrameSet ForwardKinematics(const KinematicModel& model, const JointVector& q) {
  FrameSet f;
  f.X_BL[0] = model.X_BL0;
  for (int i = 0; i < kNumLinks; ++i) {
    const double qi = i < kNumJoints ? q(i) : 0.0;
    f.X_BL[i + 1] = f.X_BL[i] * LinkTransform(model.links[i].dh, qi);
  }
  f.X_BE = f.X_BL[kNumLinks] * model.X_L7E;
  return f;
}

Transform EndPose(const KinematicModel& model, const JointVector& q) {
  return ForwardKinematics(model, q).X_BE;
}

Eigen::Matrix<double, 6, kNumJoints> ManipulatorJacobian(const KinematicModel& model,
                                                         const JointVector& q) {
  const FrameSet f = ForwardKinematics(model, q);
  const Vector3 p = f.X_BE.translation();
  Eigen::Matrix<double, 6, kNumJoints> J;
  // Joint i turns link i about the z axis of frame L(i-1).
  for (int i = 0; i < kNumJoints; ++i) {
    J.col(i) = Twist(f.X_BL[i].linear().col(2), f.X_BL[i].translation(), p);
  }
  return J;
}

Eigen::Matrix<double, kNumJoints, 1> JacobianSingularValues(const KinematicModel& model,
                                                            const JointVector& q) {
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, kNumJoints>> svd(ManipulatorJacobian(model, q));
  return svd.singularValues();
}

Eigen::Matrix<double, 6, kNumParams> IdentificationJacobian(const KinematicModel& model,
                                                            const JointVector& q) {
  // Eq. 5 differentiates each factor of eq. 2. Each parameter moves everything after it by a
  // screw: theta_i rotates about z of L(i-1) through its origin; d_i translates along that z;
  // a_i translates along x' = R_BL(i-1) RotZ(theta_i) e_x; alpha_i rotates about x' through the
  // origin of Li; beta_i rotates about y of Li (RotY leaves e_y fixed) through the same origin.
  const FrameSet f = ForwardKinematics(model, q);
  const Vector3 p = f.X_BE.translation();
  Eigen::Matrix<double, 6, kNumParams> J;
  for (int i = 0; i < kNumLinks; ++i) {
    const Transform& X_prev = f.X_BL[i];
    const Transform& X_next = f.X_BL[i + 1];
    const Vector3 z_prev = X_prev.linear().col(2);
    const Vector3 x_next = X_next.linear().col(0);
    const Vector3 y_next = X_next.linear().col(1);
    // x' is x of Li before RotY(beta): RotY(beta) turns x about y, so undo it.
    const double beta = model.links[i].dh.beta;
    const Vector3 x_mid = std::cos(beta) * x_next + std::sin(beta) * X_next.linear().col(2);
    const Vector3 o_next = X_next.translation();
    const int c = i * kParamsPerLink;
    J.col(c + static_cast<int>(DhParameter::kTheta)) = Twist(z_prev, X_prev.translation(), p);
    J.col(c + static_cast<int>(DhParameter::kD)) << z_prev, Vector3::Zero();
    J.col(c + static_cast<int>(DhParameter::kA)) << x_mid, Vector3::Zero();
    J.col(c + static_cast<int>(DhParameter::kAlpha)) = Twist(x_mid, o_next, p);
    J.col(c + static_cast<int>(DhParameter::kBeta)) = Twist(y_next, o_next, p);
  }
  return J;
}

}  // namespace twin
