// Residuals of an optical-axis sample (Zhu et al. 2019, section III.B), templated functors of
// the measured end point p = p_BE(phi, c_i) and the axis's nuisance parameters, for
// PointMeasurementCost (which joins them with the robot model).
//
// Line k: point c_k = c0_k + N_k s_k (N_k a fixed orthonormal basis of the plane through the
// initial centroid c0_k perpendicular to the initial direction; the slide of the point along
// the line, which no residual sees, is thereby removed) and direction mu_k (on the unit sphere).
#pragma once

#include <Eigen/Core>

#include "calib/kinematics/rigid_transform.h"

namespace twin {

/// Eq. 13-15: the feature point of a sample servoed onto axis k lies on the line,
/// (I - mu_k mu_k^T / |mu_k|^2)(p - o_i - c_k) = 0, with o_i the offset the camera measured when
/// the servo stopped (AxisSample::offset). Residual: that vector times `weight` (1 / sigma of
/// the perpendicular distance) [3 rows, -]. Blocks: p (3), s_k (2), mu_k (3).
struct OpticalAxisLine {
  Vector3 offset;
  Vector3 c0;
  Eigen::Matrix<double, 3, 2> N;
  const double& weight;  // owned by the measurement set; re-estimated between solves
  double scale = 1.0;    // the sample's own factor on weight (its sigma relative to the group's)

  template <typename T>
  bool operator()(const T* p, const T* s, const T* mu, T* residual) const {
    const Vec3T<T> c = c0.cast<T>() + N.col(0).cast<T>() * s[0] + N.col(1).cast<T>() * s[1];
    const Vec3T<T> m(mu[0], mu[1], mu[2]);
    const Vec3T<T> d = Vec3T<T>(p[0], p[1], p[2]) - offset.cast<T>() - c;
    const Vec3T<T> r = d - m * (d.dot(m) / m.squaredNorm());
    for (int i = 0; i < 3; ++i) residual[i] = T(weight * scale) * r(i);
    return true;
  }
};

/// The line residual of OpticalAxisLine (rows 0-2) and the scale measurement (row 3, beyond
/// the paper): the position of the feature point along the line must follow its measured depth
/// z_i (distance from the camera along the axis, from the board pose and the known square
/// length) up to one unknown offset t_k per axis (where the camera centre lies on it):
/// depth_weight (mu_k . (p - o_i - c_k) / |mu_k| - t_k - z_i). The collinearity constraint
/// cannot see a uniform scale of the arm; this row can. Blocks: p (3), s_k (2), mu_k (3), t_k (1).
struct OpticalAxisLineDepth {
  OpticalAxisLine line;
  double depth;
  const double& depth_weight;  // 1 / sigma of the depth [1/m]
  double depth_scale = 1.0;    // the sample's own factor on depth_weight

  template <typename T>
  bool operator()(const T* p, const T* s, const T* mu, const T* t, T* residual) const {
    line(p, s, mu, residual);
    const Vec3T<T> c = line.c0.cast<T>() + line.N.col(0).cast<T>() * s[0] +
                       line.N.col(1).cast<T>() * s[1];
    const Vec3T<T> m(mu[0], mu[1], mu[2]);
    const Vec3T<T> e = Vec3T<T>(p[0], p[1], p[2]) - line.offset.cast<T>() - c;
    residual[3] = T(depth_weight * depth_scale) * (e.dot(m) / m.norm() - t[0] - T(depth));
    return true;
  }
};

}  // namespace twin
