// Error model of the optical-axis (straight-line) constraint, Zhu et al. 2019, section III.B
// (eq. 10-23) and the line fit of section V.B (eq. 45-46).
//
// Setting: the passive robot's end frame E is the chessboard feature point (tool link 7). For
// each camera axis k the feature point was servoed onto that axis (a fixed line in the passive
// robot's base frame B) at several positions, and the passive robot's joint angles were
// recorded. Nominal positions p_BE = EndPose(model, q).translation() of one axis are collinear
// only if the model is right; their transversal scatter is the misaligned error.
#pragma once

#include <limits>
#include <vector>

#include <Eigen/Core>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/kinematic_model.h"
#include "calib/model/measurement_context.h"

namespace twin {

/// One recorded sample: the passive robot's joint angles q [rad] with the feature point on
/// camera axis `axis` (0-based index of the optical axis l_k).
struct AxisSample {
  int axis = 0;                        ///< optical axis index k (0-based)
  JointVector q;                       ///< recorded joint angles [rad]
  /// Residual offset of the feature point from the axis when the servo stopped, in B [m]: the
  /// servo stops within a pixel tolerance (0.1 px is 0.06 mm at 0.5 m), and the camera
  /// measures what is left; the point on the axis is p_BE(q) - offset. Zero: exactly on it.
  Vector3 offset = Vector3::Zero();
  /// Distance of the feature point from the camera along the axis [m], measured from the
  /// board's pose (known square length); NaN when not measured. Only differences between
  /// samples of one axis are used (the scale measurement of IdentifyNonlinear).
  double depth = std::numeric_limits<double>::quiet_NaN();
  /// Standard deviations of the camera's measurement of `offset` (per coordinate across the
  /// axis) and of `depth`, from the board pose's covariance (the corner noise through the
  /// camera model) [m]; 0: not known (users fall back to a stated default).
  double sigma_offset = 0.0;
  double sigma_depth = 0.0;
  /// Sign of each joint's last motion before the reading (empty: unknown); see
  /// MeasurementContext.
  JointVector approach;
  double time_s = std::numeric_limits<double>::quiet_NaN();  ///< time stamp [s]; NaN unknown
  /// Temperature change from the nominal model's reference [K]; NaN unknown.
  double temperature_delta_K = std::numeric_limits<double>::quiet_NaN();

  /// The sample's measurement context (readings, approach, time, temperature).
  MeasurementContext context() const {
    MeasurementContext c;
    c.q = q;
    c.approach = approach;
    c.time_s = time_s;
    c.temperature_delta_K = temperature_delta_K;
    return c;
  }
};

/// The point on the axis for a sample: p_BE(q) - offset [m, in B].
Vector3 AxisPoint(const KinematicModel& model, const AxisSample& sample);

/// A straight line in B: a point on it [m] and a unit direction [-].
struct Line3 {
  Vector3 point = Vector3::Zero();      ///< a point on the line (the centroid for FitLine) [m]
  Vector3 direction = Vector3::UnitZ(); ///< unit direction (mu_k of eq. 13)
};

/// Total-least-squares line through >= 2 points [m]: centroid and principal direction (SVD).
/// This is the default fit: it treats x, y, z alike, so it works for any axis direction. The
/// paper's eq. 45 regresses x and y on z, which breaks down as the axis approaches the base
/// x-y plane (its normal matrix becomes singular when all z are equal) and biases the direction
/// of tilted axes. The direction points from the first point towards the last one. Throws
/// InputError for fewer than 2 points or all points coincident.
Line3 FitLine(const std::vector<Vector3>& points);

/// The paper's eq. 45 fit: x = m z + x0, y = n z + y0, mu = (m, n, 1) normalized, point
/// (x0, y0, 0). For reference only (see FitLine). Throws InputError when the z coordinates do
/// not vary (axis perpendicular to base z).
Line3 FitLineEq45(const std::vector<Vector3>& points);

/// Misaligned error of eq. 18/46: E = [mu x](p_j - p_i) [m], mu unit, p in B [m].
Vector3 MisalignedError(const Vector3& mu, const Vector3& p_i, const Vector3& p_j);

/// Error Jacobian of eq. 19: J^(i,j,k) = [mu x](R J_P(q_i) - R J_P(q_j)), with R J_P the
/// base-frame position rows of IdentificationJacobian [m per unit parameter]. With this sign
/// E(nominal) = J dphi (eq. 20) for dphi = true - nominal parameters, i.e. J is minus the
/// derivative of MisalignedError(mu, p_i(phi), p_j(phi)) with mu held fixed.
Eigen::Matrix<double, 3, Eigen::Dynamic> ErrorJacobian(const KinematicModel& model, const Vector3& mu,
                                                   const JointVector& q_i,
                                                   const JointVector& q_j);

/// The stacked error model of eq. 21-23 over all pairs i < j of every axis (axis-major, pairs
/// in lexicographic order of their sample order within the axis).
struct MisalignedErrorStack {
  Eigen::VectorXd E;    ///< eq. 22, 3 rows per pair [m]
  Eigen::MatrixXd Phi;  ///< eq. 23, 3 rows per pair, one column per geometric parameter
  /// d E / d (axis direction) with each mu_k varied in its tangent plane (2 columns per axis,
  /// in the order of `directions`) [m per rad]. Used to profile the refitted directions out.
  Eigen::MatrixXd direction_jacobian;
  int num_pairs = 0;    ///< number of (i, j, k) pairs
  std::vector<int> axis_row_begin;  ///< first row of each axis, plus one past the end
};

/// Builds E (eq. 22) and Phi (eq. 23) from the nominal positions of `model`. `directions[k]` is
/// mu_k (unit). Preconditions (PreconditionError): every sample's axis has a direction, and
/// every direction has >= 2 samples (the caller validated the samples and fitted or planned
/// the directions for them).
MisalignedErrorStack StackMisalignedErrors(const KinematicModel& model,
                                           const std::vector<AxisSample>& samples,
                                           const std::vector<Vector3>& directions);

/// Phi with the axis-direction changes projected out: (I - A A^+) Phi, A = direction_jacobian.
/// Because the directions are refitted, only this part of Phi is seen by the data; a rigid
/// rotation of all points, for example, is absorbed by rotating the mu_k.
Eigen::MatrixXd ProfiledPhi(const MisalignedErrorStack& stack);

/// Checks recorded samples (axis indices 0..q-1, finite angles, >= 3 samples on every axis) and
/// returns q. Throws InputError naming the sample or axis.
int ValidateAxisSamples(const std::vector<AxisSample>& samples);

/// Nominal feature-point positions of each axis (index k holds axis k's points in sample
/// order) [m, in B].
std::vector<std::vector<Vector3>> AxisPoints(const KinematicModel& model,
                                             const std::vector<AxisSample>& samples);

/// TLS line (FitLine) of every axis from the model's nominal positions.
std::vector<Line3> FitAxes(const KinematicModel& model, const std::vector<AxisSample>& samples);

/// The paper's accuracy metric: mean over pairs of |E^(i,j,k)| [m], with each axis refitted by
/// FitLine from the model's nominal positions.
double MeanMisalignedErrorNorm(const KinematicModel& model,
                               const std::vector<AxisSample>& samples);

}  // namespace twin
