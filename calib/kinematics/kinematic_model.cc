#include "calib/kinematics/kinematic_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {

void RequireFinite(double v, const std::string& where, const std::string& field) {
  if (!std::isfinite(v)) throw InputError(where, field + " must be a finite number, got " +
                                                     std::to_string(v));
}

void RequireRigid(const Transform& X, const std::string& where, const std::string& field) {
  const Matrix3 R = X.linear();
  if (!X.matrix().allFinite() || (R.transpose() * R - Matrix3::Identity()).norm() > 1e-9 ||
      R.determinant() < 0.0) {
    throw InputError(where, field + " must be a rigid transform (orthonormal, right-handed)");
  }
}

}  // namespace

KinematicModel::KinematicModel(int num_joints) : links(std::max(num_joints, 0) + 1) {
  for (int i = 0; i < num_joints; ++i) links[i].name = "link" + std::to_string(i + 1);
  links.back().name = "tool";
}

Transform LinkTransform(const DhParameters& dh, double q) {
  const double p[kParamsPerLink] = {dh.theta_offset, dh.d, dh.a, dh.alpha, dh.beta};
  return ToTransform(LinkTransformT<double>(p, q, 1.0));
}

JointVector ZeroJoints(const KinematicModel& model) {
  return JointVector::Zero(model.num_joints());
}

void ValidateModel(const KinematicModel& model, const std::string& where) {
  if (model.name.empty()) throw InputError(where, "robot name must not be empty");
  if (model.num_joints() < 1 || model.num_joints() > kMaxJoints) {
    throw InputError(where, "a chain needs 1 to " + std::to_string(kMaxJoints) +
                                " revolute joints, got " + std::to_string(model.num_joints()));
  }
  RequireRigid(model.X_BL0, where, "base transform");
  RequireRigid(model.X_LtE, where, "end transform");
  const int n = model.num_joints();
  for (int i = 0; i < model.num_links(); ++i) {
    const Link& l = model.links[i];
    const std::string f = "link " + std::to_string(i + 1) + " (" + l.name + ")";
    if (l.name.empty()) throw InputError(where, f + ": name must not be empty");
    RequireFinite(l.dh.theta_offset, where, f + " theta_offset");
    RequireFinite(l.dh.d, where, f + " d");
    RequireFinite(l.dh.a, where, f + " a");
    RequireFinite(l.dh.alpha, where, f + " alpha");
    RequireFinite(l.dh.beta, where, f + " beta");
    if (i < n) {
      RequireFinite(l.limits.lower, where, f + " lower limit");
      RequireFinite(l.limits.upper, where, f + " upper limit");
      if (!(l.limits.lower < l.limits.upper)) {
        std::ostringstream os;
        os << f << ": joint lower limit " << l.limits.lower << " rad must be below upper limit "
           << l.limits.upper << " rad";
        throw InputError(where, os.str());
      }
    }
    if (!std::isfinite(l.inertia.mass) || l.inertia.mass < 0.0) {
      throw InputError(where, f + ": mass must be finite and >= 0 kg, got " +
                                  std::to_string(l.inertia.mass));
    }
    if (!l.inertia.p_LiCom.allFinite() || !l.inertia.I_Com.allFinite()) {
      throw InputError(where, f + ": centre of mass and inertia must be finite");
    }
    if ((l.inertia.I_Com - l.inertia.I_Com.transpose()).norm() > 1e-12) {
      throw InputError(where, f + ": inertia tensor must be symmetric");
    }
    if (l.inertia.mass > 0.0) {
      Eigen::SelfAdjointEigenSolver<Matrix3> eig(l.inertia.I_Com);
      const Vector3 ev = eig.eigenvalues();
      // Principal moments must be positive and satisfy the triangle inequality.
      if (ev.minCoeff() <= 0.0 || ev(0) + ev(1) < ev(2) * (1.0 - 1e-9)) {
        throw InputError(where, f + ": inertia tensor is not physical (principal moments must "
                                    "be positive and satisfy the triangle inequality)");
      }
    }
  }
}

bool WithinLimits(const KinematicModel& model, const JointVector& q) {
  if (q.size() != model.num_joints()) return false;
  for (int i = 0; i < model.num_joints(); ++i) {
    if (q(i) < model.links[i].limits.lower || q(i) > model.links[i].limits.upper) return false;
  }
  return true;
}

JointVector MidRange(const KinematicModel& model) {
  JointVector q(model.num_joints());
  for (int i = 0; i < model.num_joints(); ++i) {
    q(i) = 0.5 * (model.links[i].limits.lower + model.links[i].limits.upper);
  }
  return q;
}

JointVector NearestTurns(const KinematicModel& model, JointVector q, const JointVector& ref) {
  for (int i = 0; i < model.num_joints(); ++i) {
    const JointLimits& l = model.links[i].limits;
    const double turns = std::round((ref(i) - q(i)) / (2.0 * kPi));
    for (const double k : {turns, turns - 1.0, turns + 1.0}) {
      const double v = q(i) + 2.0 * kPi * k;
      if (v >= l.lower && v <= l.upper && std::abs(v - ref(i)) < std::abs(q(i) - ref(i))) q(i) = v;
    }
  }
  return q;
}

}  // namespace twin
