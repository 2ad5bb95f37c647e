// Residual of a laser-tracker point (the sensor model of a tracker measuring a reflector, SMR,
// on the robot's tool): the tracker reports the reflector's position m_i in its own frame T;
// the robot model predicts it in the base frame B as p = p_BE(phi, c_i), the end point of the
// model (whose tool link carries the reflector offset), so that
//   m_i = R_TB p + p_TB + noise,  noise ~ N(0, sigma_i^2 I).
// Residual (3 rows, -): weight (R_TB p + p_TB - m_i) / sigma_i, with the tracker's pose X_TB as
// nuisance parameters: a unit quaternion q_TB (Eigen order x, y, z, w, on
// ceres::EigenQuaternionManifold) and p_TB (3). Blocks: p (3), q_TB (4), p_TB (3).
#pragma once

#include <ceres/rotation.h>

#include "calib/kinematics/rigid_transform.h"

namespace twin {

struct TrackerPointResidual {
  Vector3 measured_T;    // m_i [m]
  double sigma;          // sigma_i [m]
  const double& weight;  // the set's variance-component factor (1 unless re-estimated) [-]

  template <typename T>
  bool operator()(const T* p, const T* q, const T* t, T* residual) const {
    const T wxyz[4] = {q[3], q[0], q[1], q[2]};
    T p_T[3];
    ceres::UnitQuaternionRotatePoint(wxyz, p, p_T);
    const T k = T(weight / sigma);
    for (int i = 0; i < 3; ++i) residual[i] = k * (p_T[i] + t[i] - T(measured_T(i)));
    return true;
  }
};

}  // namespace twin
