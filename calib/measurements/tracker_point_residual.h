// Residual of a laser-tracker point (the sensor model of a tracker measuring a reflector, SMR,
// on the robot's tool): the tracker reports the reflector's position m_i in its own frame T;
// the robot model predicts it in the base frame B as p_BE(phi, c_i), the end point of the model
// (whose tool link carries the reflector offset), so that
//   m_i = R_TB p_BE(phi, c_i) + p_TB + noise,  noise ~ N(0, sigma_i^2 I).
// Residual (3 rows, -): weight (R_TB p_BE + p_TB - m_i) / sigma_i, with the tracker's pose
// X_TB as nuisance parameters: a unit quaternion q_TB (Eigen order x, y, z, w, on
// ceres::EigenQuaternionManifold) and p_TB (3). Parameter blocks: the model's flat parameters,
// q_TB, p_TB.
#pragma once

#include <Eigen/Geometry>
#include <ceres/rotation.h>

#include "calib/model/robot_model.h"

namespace twin {

struct TrackerPointResidual {
  const RobotModel& model;
  MeasurementContext context;
  Vector3 measured_T;    // m_i [m]
  double sigma;          // sigma_i [m]
  const double& weight;  // the set's variance-component factor (1 unless re-estimated) [-]

  template <typename T>
  bool operator()(T const* const* blocks, T* residual) const {
    const Vec3T<T> p_B = RobotEndPoseT<T>(model, blocks[0], context).p;
    const T* q = blocks[1];  // x, y, z, w
    const T* t = blocks[2];
    const T wxyz[4] = {q[3], q[0], q[1], q[2]};
    T p_T[3];
    const T in[3] = {p_B(0), p_B(1), p_B(2)};
    ceres::UnitQuaternionRotatePoint(wxyz, in, p_T);
    const T k = T(weight / sigma);
    for (int i = 0; i < 3; ++i) residual[i] = k * (p_T[i] + t[i] - T(measured_T(i)));
    return true;
  }
};

}  // namespace twin
