#include "calib/vision/axis_start_predictor.h"

#include <cmath>
#include <string>

#include <Eigen/Cholesky>

#include "calib/common/errors.h"
#include "calib/common/text_format.h"

namespace twin {
namespace {

// The priors are the procedure's constants, no user's: a bad one is our bug.
void Positive(double v, const char* name) {
  TWIN_REQUIRE(std::isfinite(v) && v > 0,
               std::string(name) + " = " + ShortestNumber(v) + ": expected > 0");
}

}  // namespace

AxisStartPredictor::AxisStartPredictor(double prior_translation_m, double prior_rotation_rad,
                                       double scatter_m)
    : prior_translation_m_(prior_translation_m),
      prior_rotation_rad_(prior_rotation_rad),
      scatter_m_(scatter_m) {
  Positive(prior_translation_m, "prior_translation_m");
  Positive(prior_rotation_rad, "prior_rotation_rad");
  Positive(scatter_m, "scatter_m");
}

void AxisStartPredictor::Add(const Vector3& planned, const Vector3& aligned,
                             const Vector3& axis_direction) {
  const double n = axis_direction.norm();
  // A plan's position, the servo's aligned one and the fitted axis: all our own numbers.
  TWIN_REQUIRE(planned.allFinite() && aligned.allFinite() && n > 0 && std::isfinite(n),
               "a position with a non-finite point or a zero axis");
  const Vector3 d = axis_direction / n;
  const Matrix3 across = Matrix3::Identity() - d * d.transpose();  // what the servo sees
  // across (t + w x p) = across (t - [p]x w) = across (aligned - planned)
  Eigen::Matrix<double, 3, 6> a;
  a.leftCols<3>() = across;
  a.rightCols<3>() = -across * SkewMatrix(planned);
  const Vector3 b = across * (aligned - planned);
  const double w = 1.0 / (scatter_m_ * scatter_m_);
  normal_ += w * a.transpose() * a;
  rhs_ += w * a.transpose() * b;
  ++positions_;
}

Eigen::Matrix<double, 6, 1> AxisStartPredictor::Solve() const {
  if (positions_ == 0) return Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> n = normal_;
  const double pt = 1.0 / (prior_translation_m_ * prior_translation_m_);
  const double pr = 1.0 / (prior_rotation_rad_ * prior_rotation_rad_);
  for (int i = 0; i < 3; ++i) {
    n(i, i) += pt;
    n(i + 3, i + 3) += pr;
  }
  return n.ldlt().solve(rhs_);  // positive definite: the ridge
}

Vector3 AxisStartPredictor::Correction(const Vector3& planned) const {
  const Eigen::Matrix<double, 6, 1> x = Solve();
  return x.head<3>() + x.tail<3>().cross(planned);
}

Vector3 AxisStartPredictor::translation() const { return Solve().head<3>(); }
Vector3 AxisStartPredictor::rotation() const { return Solve().tail<3>(); }

}  // namespace twin
