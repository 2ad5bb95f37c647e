#include "bench/io/plausibility.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace twin::plausibility {
namespace {

constexpr double kDeg = kPi / 180.0;

TEST(Plausibility, LengthsUpToTenMetres) {
  EXPECT_FALSE(LengthProblem(0.0));
  EXPECT_FALSE(LengthProblem(-10.0));
  EXPECT_TRUE(LengthProblem(10.001));
  EXPECT_TRUE(LengthProblem(1e308));
  EXPECT_TRUE(LengthProblem(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_NE(LengthProblem(1e6)->find("got 1e+06 m"), std::string::npos) << *LengthProblem(1e6);
}

TEST(Plausibility, AnglesWithinATurnAndLimitsWithinTwo) {
  EXPECT_FALSE(AngleProblem(2 * kPi, "rad", 1.0));
  EXPECT_TRUE(AngleProblem(361 * kDeg, "deg", kDeg));
  EXPECT_NE(AngleProblem(400 * kDeg, "deg", kDeg)->find("+-360 deg"), std::string::npos);
  EXPECT_FALSE(JointLimitProblem(-720 * kDeg, "deg", kDeg));
  EXPECT_TRUE(JointLimitProblem(721 * kDeg, "deg", kDeg));
}

TEST(Plausibility, MassesBetweenZeroAndTenTonnes) {
  EXPECT_FALSE(MassProblem(0.0));
  EXPECT_FALSE(MassProblem(1e4));
  EXPECT_TRUE(MassProblem(-1e-9));
  EXPECT_TRUE(MassProblem(1.0001e4));
  EXPECT_TRUE(MassProblem(std::numeric_limits<double>::quiet_NaN()));
}

TEST(Plausibility, InertiaMustBePhysical) {
  const Matrix3 box = Vector3(0.02, 0.03, 0.04).asDiagonal();
  EXPECT_FALSE(InertiaProblem(2.0, box));
  EXPECT_FALSE(InertiaProblem(0.0, Matrix3::Zero()));
  EXPECT_TRUE(InertiaProblem(0.0, box));                                  // massless with inertia
  EXPECT_TRUE(InertiaProblem(2.0, Matrix3::Zero()));                      // mass without it
  EXPECT_TRUE(InertiaProblem(2.0, Vector3(0.01, 0.01, 0.05).asDiagonal()));  // triangle
  EXPECT_TRUE(InertiaProblem(2.0, Vector3(-0.01, 0.02, 0.02).asDiagonal()));
  EXPECT_TRUE(InertiaProblem(2.0, Vector3(300, 300, 300).asDiagonal()));  // beyond 2 kg (10 m)^2
  Matrix3 skew = box;
  skew(0, 1) = 0.001;
  EXPECT_TRUE(InertiaProblem(2.0, skew));                                 // not symmetric
}

}  // namespace
}  // namespace twin::plausibility
