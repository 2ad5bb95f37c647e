// Where the servo should start the first position of a new axis. The plan puts the feature
// point P on each camera axis using the rough base-to-base transform and nominal models, so
// every planned position misses by what those get wrong: mostly a rigid motion of the passive
// base as the estimator sees it (a base told 30 mm / 3 deg off moves a point 1 m away by up to
// ~80 mm), plus kinematic errors that change slowly over the workspace. Each aligned position
// shows that miss, perpendicular to its axis (the servo moves P across the axis, never along
// it). Fitting a small rigid motion (t, w) to those misses,
//     aligned - planned  ~  t + w x planned      (only the part across the axis is seen),
// predicts the miss at the next axis's first position, so the servo starts close instead of
// one or several max_step_m moves away.
#pragma once

#include <Eigen/Core>

#include "calib/common/frames.h"

namespace twin {

/// Least-squares fit of a small rigid motion of the passive base to the servo's corrections,
/// regularized toward no motion (a ridge: with one axis's positions, all on a line, the fit
/// is the smallest motion that explains them). Points in the passive base frame [m].
class AxisStartPredictor {
 public:
  /// prior_translation_m, prior_rotation_rad: a priori size of t and w (the ridge), so a few
  /// positions cannot swing the prediction far; scatter_m: how far one position's miss is
  /// from the rigid model (kinematic errors, the servo's tolerance), the misses' weight.
  explicit AxisStartPredictor(double prior_translation_m = 0.1, double prior_rotation_rad = 0.1,
                              double scatter_m = 0.002);
  /// One aligned position: the planned P, the aligned P (both by the same nominal forward
  /// kinematics) and the camera axis's direction, all in the passive base frame.
  void Add(const Vector3& planned, const Vector3& aligned, const Vector3& axis_direction);
  int positions() const { return positions_; }
  /// The predicted miss at `planned` (to add to it); zero before any position was added.
  Vector3 Correction(const Vector3& planned) const;
  /// The fitted rigid motion: translation [m] and small rotation vector [rad].
  Vector3 translation() const;
  Vector3 rotation() const;

 private:
  Eigen::Matrix<double, 6, 1> Solve() const;
  double prior_translation_m_, prior_rotation_rad_, scatter_m_;
  Eigen::Matrix<double, 6, 6> normal_ = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs_ = Eigen::Matrix<double, 6, 1>::Zero();
  int positions_ = 0;
};

}  // namespace twin
