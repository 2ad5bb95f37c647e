#include "calib/kinematics/forward_kinematics.h"

#include <cmath>
#include <string>

#include <Eigen/SVD>

#include "calib/common/errors.h"

namespace twin {
namespace {

Eigen::Matrix<double, 6, 1> Twist(const Vector3& axis, const Vector3& point_on_axis,
                                  const Vector3& p) {
  Eigen::Matrix<double, 6, 1> col;
  col << axis.cross(p - point_on_axis), axis;
  return col;
}

// q has one angle per joint of `model` (callers pass their own model's readings).
void RequireJointCount(const KinematicModel& model, const JointVector& q) {
  TWIN_REQUIRE(q.size() == model.num_joints(),
               std::to_string(q.size()) + " joint angles for a " +
                   std::to_string(model.num_joints()) + "-joint chain");
}

// The model's geometric parameters in a stack buffer (no allocation per FK call).
struct FlatParameters {
  std::array<double, kParamsPerLink * (kMaxJoints + 1)> phi;
  explicit FlatParameters(const KinematicModel& m) {
    TWIN_REQUIRE(m.num_joints() >= 1 && m.num_joints() <= kMaxJoints,
                 std::to_string(m.num_joints()) + " joints, expected 1.." +
                     std::to_string(kMaxJoints));
    for (int i = 0; i < m.num_links(); ++i) {
      const DhParameters& dh = m.links[i].dh;
      double* p = phi.data() + kParamsPerLink * i;
      p[0] = dh.theta_offset;
      p[1] = dh.d;
      p[2] = dh.a;
      p[3] = dh.alpha;
      p[4] = dh.beta;
    }
  }
};

}  // namespace

ChainTrig::ChainTrig(const KinematicModel& model) {
  TWIN_REQUIRE(model.num_links() <= kMaxJoints + 1,
               std::to_string(model.num_links()) + " links, expected at most " +
                   std::to_string(kMaxJoints + 1));
  for (int i = 0; i < model.num_links(); ++i) {
    const DhParameters& dh = model.links[i].dh;
    link[i] = {std::cos(dh.alpha), std::sin(dh.alpha), std::cos(dh.beta), std::sin(dh.beta)};
  }
}

namespace {

// ChainFramesT in double into `f` (ForwardKinematics' frames); returns the chain's last frame
// as computed, before its conversion (EndPose's product continues from it).
RigidT<double> ChainFrameSet(const KinematicModel& model, const JointVector& q,
                             const ChainTrig* trig, FrameSet* f) {
  RequireJointCount(model, q);
  const FlatParameters flat(model);
  std::array<RigidT<double>, kMaxJoints + 2> X;
  ChainFramesT<double>(model, flat.phi.data(), q.data(), 1.0, X.data(),
                       trig ? trig->link.data() : nullptr);
  const int links = model.num_links();
  f->num_joints = model.num_joints();
  for (int i = 0; i <= links; ++i) f->X_BL[i] = ToTransform(X[i]);
  f->X_BE = f->X_BL[links] * model.X_LtE;
  return X[links];
}

}  // namespace

FrameSet ForwardKinematics(const KinematicModel& model, const JointVector& q,
                           const ChainTrig* trig) {
  FrameSet f;
  ChainFrameSet(model, q, trig, &f);
  return f;
}

Transform EndPose(const KinematicModel& model, const JointVector& q, const ChainTrig* trig) {
  RequireJointCount(model, q);
  const FlatParameters flat(model);
  return ToTransform(ChainEndPoseT<double>(model, flat.phi.data(), q.data(), 1.0,
                                           trig ? trig->link.data() : nullptr));
}

Transform FramesAndEndPose(const KinematicModel& model, const JointVector& q,
                           const ChainTrig* trig, FrameSet* frames) {
  // ChainEndPoseT's last step on the same chain product.
  return ToTransform(ChainFrameSet(model, q, trig, frames) *
                     RigidT<double>::FromTransform(model.X_LtE));
}

JointJacobian ManipulatorJacobian(const KinematicModel& model, const JointVector& q,
                                  const ChainTrig* trig) {
  return ManipulatorJacobian(ForwardKinematics(model, q, trig));
}

JointJacobian ManipulatorJacobian(const FrameSet& f) {
  const Vector3 p = f.X_BE.translation();
  const int n = f.num_joints;
  JointJacobian J(6, n);
  // Joint i turns link i about the z axis of frame L(i-1).
  for (int i = 0; i < n; ++i) {
    J.col(i) = Twist(f.X_BL[i].linear().col(2), f.X_BL[i].translation(), p);
  }
  return J;
}

Eigen::VectorXd JacobianSingularValues(const KinematicModel& model, const JointVector& q,
                                       const ChainTrig* trig) {
  const Eigen::JacobiSVD<JointJacobian> svd(ManipulatorJacobian(model, q, trig));
  return svd.singularValues();
}

double SmallestJacobianSingularValue(const KinematicModel& model, const JointVector& q,
                                     const ChainTrig* trig) {
  const Eigen::VectorXd s = JacobianSingularValues(model, q, trig);
  return s(s.size() - 1);
}

void IdentificationColumns(int num_links, const RigidT<double>* X, const double* phi,
                           const Vector3& p, double s, ParameterJacobian* J) {
  // Eq. 5 differentiates each factor of eq. 2. Each parameter moves everything after it by a
  // screw: theta_i rotates about z of L(i-1) through its origin; d_i translates along that z;
  // a_i translates along x' = R_BL(i-1) RotZ(theta_i) e_x; alpha_i rotates about x' through the
  // origin of Li; beta_i rotates about y of Li (RotY leaves e_y fixed) through the same origin.
  J->resize(6, kParamsPerLink * num_links);
  for (int i = 0; i < num_links; ++i) {
    const RigidT<double>& X_prev = X[i];
    const RigidT<double>& X_next = X[i + 1];
    const Vector3 z_prev = X_prev.R.col(2);
    // x' is x of Li before RotY(beta): RotY(beta) turns x about y, so undo it.
    const double beta = phi[kParamsPerLink * i + static_cast<int>(DhParameter::kBeta)];
    const Vector3 x_mid = std::cos(beta) * X_next.R.col(0) + std::sin(beta) * X_next.R.col(2);
    const int c = i * kParamsPerLink;
    J->col(c + static_cast<int>(DhParameter::kTheta)) = Twist(z_prev, X_prev.p, p);
    J->col(c + static_cast<int>(DhParameter::kD)) << s * z_prev, Vector3::Zero();
    J->col(c + static_cast<int>(DhParameter::kA)) << s * x_mid, Vector3::Zero();
    J->col(c + static_cast<int>(DhParameter::kAlpha)) = Twist(x_mid, X_next.p, p);
    J->col(c + static_cast<int>(DhParameter::kBeta)) = Twist(X_next.R.col(1), X_next.p, p);
  }
}

ParameterJacobian IdentificationJacobian(const KinematicModel& model, const JointVector& q) {
  RequireJointCount(model, q);
  const FlatParameters flat(model);
  std::array<RigidT<double>, kMaxJoints + 2> X;
  ChainFramesT<double>(model, flat.phi.data(), q.data(), 1.0, X.data());
  const Vector3 p = X[model.num_links()] * model.X_LtE.translation();
  ParameterJacobian J;
  IdentificationColumns(model.num_links(), X.data(), flat.phi.data(), p, 1.0, &J);
  return J;
}

}  // namespace twin
