#include "calib/kinematics/kinematic_model.h"

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "test_models.h"

namespace twin {
namespace {

// Eq. 2 composed from elementary transforms, independently of LinkTransform's closed form.
Transform Composed(const DhParameters& dh, double q) {
  Transform X = Transform::Identity();
  X.rotate(Eigen::AngleAxisd(dh.theta_offset + q, Vector3::UnitZ()));
  X.translate(Vector3(0, 0, dh.d));
  X.translate(Vector3(dh.a, 0, 0));
  X.rotate(Eigen::AngleAxisd(dh.alpha, Vector3::UnitX()));
  X.rotate(Eigen::AngleAxisd(dh.beta, Vector3::UnitY()));
  return X;
}

std::string ErrorOf(const KinematicModel& m) {
  try {
    ValidateModel(m, "test.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(LinkTransform, MatchesElementaryComposition) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int k = 0; k < 500; ++k) {
    const DhParameters dh{u(rng), 0.2 * u(rng), 0.2 * u(rng), u(rng), u(rng)};
    const double q = u(rng);
    // 1e-14: both sides are a few double-precision products of unit-scale numbers.
    EXPECT_LT((LinkTransform(dh, q).matrix() - Composed(dh, q).matrix()).norm(), 1e-14);
  }
}

TEST(LinkTransform, ZeroBetaIsClassicDh) {
  // Eq. 3 written out entry by entry.
  const double th = 0.7, d = 0.1, a = 0.25, al = -1.1;
  const Transform X = LinkTransform({th, d, a, al, 0.0}, 0.0);
  Eigen::Matrix4d eq3;
  eq3 << std::cos(th), -std::sin(th) * std::cos(al), std::sin(th) * std::sin(al), a * std::cos(th),
      std::sin(th), std::cos(th) * std::cos(al), -std::cos(th) * std::sin(al), a * std::sin(th),
      0, std::sin(al), std::cos(al), d, 0, 0, 0, 1;
  EXPECT_LT((X.matrix() - eq3).norm(), 1e-15);  // same formula, rounding only
}

TEST(ValidateModel, AcceptsTheReferenceModel) {
  EXPECT_EQ(ErrorOf(testing::ReinovoLikeModel()), "");
}

TEST(ValidateModel, RejectsInvertedLimitsNamingTheLink) {
  KinematicModel m = testing::ReinovoLikeModel();
  m.links[2].limits = {0.5, -0.5};
  const std::string msg = ErrorOf(m);
  EXPECT_NE(msg.find("test.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("link 3 (link3)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lower limit"), std::string::npos) << msg;
}

TEST(ValidateModel, RejectsNonFiniteParameter) {
  KinematicModel m = testing::ReinovoLikeModel();
  m.links[4].dh.alpha = std::nan("");
  const std::string msg = ErrorOf(m);
  EXPECT_NE(msg.find("link 5 (link5) alpha must be a finite number"), std::string::npos) << msg;
}

TEST(ValidateModel, RejectsUnphysicalInertia) {
  KinematicModel m = testing::ReinovoLikeModel();
  m.links[1].inertia.mass = 2.0;
  m.links[1].inertia.I_Com = Eigen::Vector3d(1.0, 0.1, 0.1).asDiagonal();  // 0.1 + 0.1 < 1
  EXPECT_NE(ErrorOf(m).find("inertia tensor is not physical"), std::string::npos);
  m.links[1].inertia.mass = -1.0;
  EXPECT_NE(ErrorOf(m).find("mass must be finite and >= 0"), std::string::npos);
}

TEST(ValidateModel, RejectsNonRigidBaseTransform) {
  KinematicModel m = testing::ReinovoLikeModel();
  m.X_BL0.linear() *= 2.0;
  EXPECT_NE(ErrorOf(m).find("base transform must be a rigid transform"), std::string::npos);
}

TEST(JointLimits, WithinLimitsAndMidRange) {
  const KinematicModel m = testing::ReinovoLikeModel();
  const JointVector mid = MidRange(m);
  EXPECT_TRUE(WithinLimits(m, mid));
  JointVector q = mid;
  q(5) = m.links[5].limits.upper + 1e-9;
  EXPECT_FALSE(WithinLimits(m, q));
  q(5) = m.links[5].limits.upper;  // limits are inclusive
  EXPECT_TRUE(WithinLimits(m, q));
}

// Whole turns only, to the angle nearest the reference inside the limits: a +-360 deg joint at
// -310 deg next to a reference of 0 goes to 50 deg; a +-180 deg joint stays where no turned
// angle fits (170 deg next to -170 deg: 170 - 360 = -190 is outside); a turn that moves away
// from the reference is not made.
TEST(NearestTurns, TurnsByWholeTurnsTowardsTheReferenceInsideTheLimits) {
  KinematicModel m = testing::ReinovoLikeModel();
  m.links[0].limits = JointLimits{-2 * kPi, 2 * kPi};
  m.links[1].limits = JointLimits{-kPi, kPi};
  const auto deg = [](double d) { return DegToRad(d); };
  JointVector q = JointVector::Zero(6), ref = JointVector::Zero(6);
  q(0) = deg(-310);
  q(1) = deg(170);
  ref(1) = deg(-170);
  q(2) = deg(10);
  const JointVector r = NearestTurns(m, q, ref);
  EXPECT_NEAR(RadToDeg(r(0)), 50.0, 1e-9);
  EXPECT_NEAR(RadToDeg(r(1)), 170.0, 1e-9);
  EXPECT_NEAR(RadToDeg(r(2)), 10.0, 1e-9);
  // Every joint keeps its pose: the angles differ by whole turns.
  for (int i = 0; i < 6; ++i) {
    const double turns = (r(i) - q(i)) / (2 * kPi);
    EXPECT_NEAR(turns, std::round(turns), 1e-12) << i;
  }
}

}  // namespace
}  // namespace twin
