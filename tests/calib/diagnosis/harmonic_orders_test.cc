// The harmonic orders discovery tries per joint (calib/diagnosis/harmonic_orders.h): the range
// a joint's readings resolve, and the orders the residual's spectrum over it picks.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "calib/diagnosis/harmonic_orders.h"

namespace twin::discovery {
namespace {

TEST(HarmonicOrders, TheSampledRangeBoundsTheOrder) {
  // 11 distinct readings over 1 rad: spacing 0.1 rad, pi / 0.1 = 31.4 -> capped at 8.
  std::vector<double> q;
  for (int i = 0; i <= 10; ++i) q.push_back(0.1 * i);
  EXPECT_EQ(ResolvedOrder(q, 8), 8);
  // 4 distinct readings over 3 rad: pi * 3 / 3 = 3.14 -> 3.
  EXPECT_EQ(ResolvedOrder({0.0, 1.0, 2.0, 3.0, 3.0, 3.0 + 1e-9}, 8), 3);
  // A joint that does not move, or moves to two places only, resolves nothing.
  EXPECT_EQ(ResolvedOrder({0.5, 0.5, 0.5}, 8), 0);
  EXPECT_EQ(ResolvedOrder({0.5, 0.7, 0.5, 0.7}, 8), 0);
}

TEST(HarmonicOrders, TheSpectrumPicksTheOrdersInTheResidual) {
  // A residual with a 3rd and a 5th harmonic of joint 2's reading (amplitudes 3 and 1 um) in
  // noise of 0.3 um, joint 1 at random; each joint's two strongest orders.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-2.5, 2.5);
  std::normal_distribution<double> noise(0.0, 0.3e-6);
  const int n = 300;
  std::vector<MeasurementContext> c(n);
  std::vector<Eigen::VectorXd> e(n);
  for (int i = 0; i < n; ++i) {
    c[i].q = JointVector::Zero(2);
    c[i].q << angle(rng), angle(rng);
    const double q2 = c[i].q(1);
    e[i] = Eigen::Vector3d(3e-6 * std::sin(3 * q2) + noise(rng), noise(rng),
                           1e-6 * std::cos(5 * q2) + noise(rng));
  }
  std::vector<const MeasurementContext*> ptr(n);
  for (int i = 0; i < n; ++i) ptr[i] = &c[i];
  const auto orders = SpectrumOrders(e, ptr, 2, 8, 2);
  ASSERT_EQ(orders.size(), 2u);
  EXPECT_EQ(orders[1], (std::vector<int>{3, 5}));
  EXPECT_EQ(orders[0].size(), 2u);  // noise only: two orders all the same, none of them named
  // The power at order 3 is what its fit explains: about n * A^2 / 2 = 1.35e-9 m^2 (the
  // noise adds ~3 * 0.3e-6^2 per order; 20 % covers the sampling's spread).
  std::vector<double> q2(n);
  for (int i = 0; i < n; ++i) q2[i] = c[i].q(1);
  const std::vector<double> power = HarmonicPower(e, q2, 8);
  ASSERT_EQ(power.size(), 8u);
  EXPECT_NEAR(power[2], n * 9e-12 / 2, 0.2 * n * 9e-12 / 2);
  EXPECT_LT(power[0], 0.1 * power[2]);
}

// A joint-angle error of order 3, dq = A sin(3 q), seen at a point a lever arm L from the
// axis, which turns with the joint: in the fixed frame the point moves by L dq (-sin q, cos q),
// products of order 3 and order 1, so the fixed-frame spectrum shows orders 2 and 4 (3 - 1 and
// 3 + 1), not 3. In the link's frame, which turns with the joint, the same residual is
// L dq (0, 1): order 3 alone. (Why discovery reads each joint's spectrum in its link's frame.)
TEST(HarmonicOrders, InTheLinksFrameAnErrorTurningWithTheJointKeepsItsOrder) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(-2.5, 2.5);
  const double A = 1e-4, L = 0.8;
  std::vector<Eigen::VectorXd> fixed, link;
  std::vector<MeasurementContext> contexts(300);
  std::vector<const MeasurementContext*> pointers;
  for (MeasurementContext& c : contexts) {
    const double q = angle(rng);
    c.q = JointVector::Zero(1);
    c.q(0) = q;
    const double dq = A * std::sin(3 * q + 0.4);
    fixed.push_back(Eigen::Vector3d(-L * dq * std::sin(q), L * dq * std::cos(q), 0.0));
    link.push_back(Eigen::Vector3d(0.0, L * dq, 0.0));
    pointers.push_back(&c);
  }
  EXPECT_EQ(SpectrumOrders(fixed, pointers, 1, 8, 2), (std::vector<std::vector<int>>{{2, 4}}));
  // Order 3 is the strongest in the link's frame: alone with per_joint 1.
  EXPECT_EQ(SpectrumOrdersPerJoint({link}, pointers, 8, 1),
            (std::vector<std::vector<int>>{{3}}));
}

TEST(HarmonicOrders, TheFundamentalIsAlwaysTried) {
  // Added where missing, kept once where present, ascending; a joint without orders (it does
  // not move) stays without.
  EXPECT_EQ(WithFundamental({{2, 5, 8}, {1, 3}, {}, {3}}),
            (std::vector<std::vector<int>>{{1, 2, 5, 8}, {1, 3}, {}, {1, 3}}));
}

}  // namespace
}  // namespace twin::discovery
