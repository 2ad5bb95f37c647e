#include "calib/diagnosis/evidence.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin::discovery {
namespace {

TEST(Evidence, CorrelationsAreSortedByStrengthAndCapped) {
  // Residual x = 2 t (r = 1 with t), y = -t (r = -1), z constant (r = 0 by definition); q is
  // (t - 2.5)^2, symmetric about the middle, so uncorrelated with t: r = 0 exactly.
  const std::vector<double> t{0, 1, 2, 3, 4, 5};
  std::vector<double> x, y, z, sq;
  for (double v : t) {
    x.push_back(2 * v);
    y.push_back(-v);
    z.push_back(1.0);
    sq.push_back((v - 2.5) * (v - 2.5));
  }
  const std::vector<Quantity> quantities{{"q", "rad", sq}, {"time", "s", t}};
  const Components components{{"x", x}, {"y", y}, {"z", z}};
  const std::vector<ResidualCorrelation> all = StrongestCorrelations(quantities, components, 8);
  ASSERT_EQ(all.size(), 6u);
  // |r| = 1 first, in quantity-major order (stable), then the zeros. 1e-12: rounding of sums
  // of six small integers.
  EXPECT_EQ(all[0].quantity, "time");
  EXPECT_EQ(all[0].component, "x");
  EXPECT_NEAR(all[0].r, 1.0, 1e-12);
  EXPECT_EQ(all[1].component, "y");
  EXPECT_NEAR(all[1].r, -1.0, 1e-12);
  for (int k = 2; k < 6; ++k) EXPECT_NEAR(all[k].r, 0.0, 1e-12) << k;
  EXPECT_EQ(StrongestCorrelations(quantities, components, 2).size(), 2u);
}

TEST(Evidence, AMapBinsTheResidualAlongTheQuantity) {
  // 0..7 over 8 bins of width 7/8: one value a bin; bin b holds the residual of distance b.
  Quantity q{"q1", "rad", {0, 1, 2, 3, 4, 5, 6, 7}};
  std::vector<double> dist2;
  for (int b = 0; b < 8; ++b) dist2.push_back(b * b);
  const ResidualMap m = MapAlong(q, dist2);
  ASSERT_EQ(m.count.size(), 8u);
  for (int b = 0; b < 8; ++b) {
    EXPECT_EQ(m.count[b], 1) << b;
    EXPECT_DOUBLE_EQ(m.rms_m[b], b) << b;
    EXPECT_DOUBLE_EQ(m.bin_centre[b], (b + 0.5) * 7.0 / 8.0) << b;
  }
  // A constant quantity: one bin with everything, its RMS over all (sqrt((1 + 9) / 2)).
  const ResidualMap flat = MapAlong({"t", "s", {2.0, 2.0}}, {1.0, 9.0});
  ASSERT_EQ(flat.count, std::vector<int>{2});
  EXPECT_DOUBLE_EQ(flat.rms_m[0], std::sqrt(5.0));
  EXPECT_THROW(MapAlong(q, {1.0}), PreconditionError);
}

}  // namespace
}  // namespace twin::discovery
