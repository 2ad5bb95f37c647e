// A rigid transform on any scalar (double or ceres::Jet), the building block of the one forward
// kinematics (forward_kinematics.h) that every solver, the planner and IK use. Frames follow
// calib/common/frames.h: X_AB maps coordinates in B to coordinates in A.
#pragma once

#include <Eigen/Core>

#include "calib/common/frames.h"

namespace twin {

template <typename T>
using Vec3T = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3T = Eigen::Matrix<T, 3, 3>;

/// Rotation R and translation p of a rigid transform X_AB on scalar T (p = p_AB, the origin of B
/// in A).
template <typename T>
struct RigidT {
  Mat3T<T> R = Mat3T<T>::Identity();
  Vec3T<T> p = Vec3T<T>::Zero();

  /// X_AC = X_AB * X_BC.
  RigidT operator*(const RigidT& X_BC) const { return {R * X_BC.R, p + R * X_BC.p}; }
  /// p_AQ = X_AB * p_BQ.
  Vec3T<T> operator*(const Vec3T<T>& p_BQ) const { return p + R * p_BQ; }

  /// A double transform promoted to T (constant entries).
  static RigidT FromTransform(const Transform& X) {
    return {X.linear().cast<T>(), X.translation().cast<T>()};
  }
};

/// The double RigidT as an Eigen isometry.
inline Transform ToTransform(const RigidT<double>& X) {
  Transform out = Transform::Identity();
  out.linear() = X.R;
  out.translation() = X.p;
  return out;
}

}  // namespace twin
