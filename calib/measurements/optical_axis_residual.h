// Residuals of an optical-axis sample (Zhu et al. 2019, section III.B), templated functors for
// ceres::DynamicAutoDiffCostFunction. Parameter blocks: the robot model's flat parameters
// (ParameterLayout order), then the axis's line: s_k (2) and mu_k (3, on the unit sphere), and
// for the depth residual t_k (1).
//
// Line k: point c_k = c0_k + N_k s_k (N_k a fixed orthonormal basis of the plane through the
// initial centroid c0_k perpendicular to the initial direction; the slide of the point along
// the line, which no residual sees, is thereby removed) and direction mu_k.
#pragma once

#include <Eigen/Core>

#include "calib/model/robot_model.h"

namespace twin {

/// Eq. 13-15: the feature point p_BE(phi, c_i) of a sample servoed onto axis k lies on the
/// line, (I - mu_k mu_k^T / |mu_k|^2)(p_BE - o_i - c_k) = 0, with o_i the offset the camera
/// measured when the servo stopped (AxisSample::offset). Residual: that vector times `weight`
/// (1 / sigma of the perpendicular distance) [3 rows, -].
struct OpticalAxisResidual {
  const RobotModel& model;
  MeasurementContext context;
  Vector3 offset;
  Vector3 c0;
  Eigen::Matrix<double, 3, 2> N;
  const double& weight;  // owned by the measurement set; re-estimated between solves

  template <typename T>
  bool operator()(T const* const* blocks, T* residual) const {
    const T* s = blocks[1];
    const T* mu = blocks[2];
    const Vec3T<T> p = RobotEndPoseT<T>(model, blocks[0], context).p - offset.cast<T>();
    const Vec3T<T> c = c0.cast<T>() + N.col(0).cast<T>() * s[0] + N.col(1).cast<T>() * s[1];
    const Vec3T<T> m(mu[0], mu[1], mu[2]);
    const Vec3T<T> d = p - c;
    const Vec3T<T> r = d - m * (d.dot(m) / m.squaredNorm());
    for (int i = 0; i < 3; ++i) residual[i] = T(weight) * r(i);
    return true;
  }
};

/// The scale measurement (beyond the paper): the position of the feature point along the line
/// must follow its measured depth z_i (distance from the camera along the axis, from the board
/// pose and the known square length) up to one unknown offset t_k per axis (where the camera
/// centre lies on the line): residual weight (mu_k . (p_i - c_k) / |mu_k| - t_k - z_i) [1 row].
/// The collinearity constraint cannot see a uniform scale of the arm; this residual can.
struct OpticalAxisDepthResidual {
  const RobotModel& model;
  MeasurementContext context;
  Vector3 offset;
  Vector3 c0;
  Eigen::Matrix<double, 3, 2> N;
  double depth;
  const double& weight;  // 1 / sigma of the depth [1/m]

  template <typename T>
  bool operator()(T const* const* blocks, T* residual) const {
    const T* s = blocks[1];
    const T* mu = blocks[2];
    const T* t = blocks[3];
    const Vec3T<T> p = RobotEndPoseT<T>(model, blocks[0], context).p - offset.cast<T>();
    const Vec3T<T> c = c0.cast<T>() + N.col(0).cast<T>() * s[0] + N.col(1).cast<T>() * s[1];
    const Vec3T<T> m(mu[0], mu[1], mu[2]);
    residual[0] = T(weight) * ((p - c).dot(m) / m.norm() - t[0] - T(depth));
    return true;
  }
};

}  // namespace twin
