#include "bench/io/plausibility.h"

#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calib/common/text_format.h"

namespace twin::plausibility {
namespace {

std::string N(double v) { return ShortestNumber(v); }

}  // namespace

std::optional<std::string> LengthProblem(double value_m) {
  if (std::isfinite(value_m) && std::abs(value_m) <= kMaxLinkLengthM) return std::nullopt;
  return "must be within +-" + N(kMaxLinkLengthM) + " m (no industrial arm has a link or "
         "offset longer than about 4 m; a larger value is usually millimetres read as metres), "
         "got " + N(value_m) + " m";
}

std::optional<std::string> AngleProblem(double value_rad, const std::string& unit,
                                        double scale) {
  if (std::isfinite(value_rad) && std::abs(value_rad) <= kMaxAngleRad * (1 + 1e-12)) {
    return std::nullopt;
  }
  return "must be within one turn, +-" + N(kMaxAngleRad / scale) + " " + unit +
         " (angles are periodic; a larger value is usually degrees written as radians), got " +
         N(value_rad / scale) + " " + unit;
}

std::optional<std::string> JointLimitProblem(double value_rad, const std::string& unit,
                                             double scale) {
  if (std::isfinite(value_rad) && std::abs(value_rad) <= kMaxJointTravelRad * (1 + 1e-12)) {
    return std::nullopt;
  }
  return "must be within two turns, +-" + N(kMaxJointTravelRad / scale) + " " + unit +
         " (no joint travels further; a larger value is usually degrees written as radians), "
         "got " + N(value_rad / scale) + " " + unit;
}

std::optional<std::string> MassProblem(double mass_kg) {
  if (std::isfinite(mass_kg) && mass_kg >= 0.0 && mass_kg <= kMaxLinkMassKg) return std::nullopt;
  return "mass must be in [0, " + N(kMaxLinkMassKg) + "] kg (a link of the heaviest industrial "
         "robots weighs about a tonne; negative or NaN masses do not exist), got " +
         N(mass_kg) + " kg";
}

std::optional<std::string> InertiaProblem(double mass_kg, const Matrix3& I) {
  if (!I.allFinite()) return std::string("inertia must be finite");
  if ((I - I.transpose()).norm() > 1e-12 * (1.0 + I.norm())) {
    return std::string("inertia tensor must be symmetric");
  }
  if (!(mass_kg > 0.0)) {
    if (I.norm() == 0.0) return std::nullopt;
    return std::string("inertia must be zero for a link without mass (a massless body has no "
                       "moment of inertia)");
  }
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(I);
  const Vector3 ev = eig.eigenvalues();  // ascending
  std::ostringstream moments;
  moments << "principal moments " << N(ev(0)) << ", " << N(ev(1)) << ", " << N(ev(2))
          << " kg m^2";
  if (!(ev(0) > 0.0)) {
    return "inertia tensor is not physical: principal moments must be > 0 for a body with mass, "
           "got " + moments.str();
  }
  if (ev(0) + ev(1) < ev(2) * (1.0 - 1e-9)) {
    return "inertia tensor is not physical: no principal moment may exceed the sum of the other "
           "two (triangle inequality), got " + moments.str();
  }
  const double largest = mass_kg * kMaxLinkLengthM * kMaxLinkLengthM;
  if (ev(2) > largest) {
    return "inertia tensor is not plausible: a principal moment above mass x (" +
           N(kMaxLinkLengthM) + " m)^2 = " + N(largest) + " kg m^2 needs a body reaching beyond " +
           N(kMaxLinkLengthM) + " m, got " + moments.str();
  }
  return std::nullopt;
}

}  // namespace twin::plausibility
