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

}  // namespace
}  // namespace twin::discovery
