// SplitAxes (calib/procedures/optical_axis_procedure.h): the calibration/validation split by whole axes.
#include "calib/procedures/optical_axis_procedure.h"

#include <algorithm>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/identification/nonlinear_identification.h"
#include "calib/model/parameters.h"
#include "optical_axis_synthetic.h"

namespace twin {
namespace {

using testing::MakeOpticalAxisScenario;

// Synthetic 5-axis data in which axis 4 repeats axis 0's poses: a calibration set holding
// both carries only two axes' information, so it is the worst conditioned.
std::vector<AxisSample> WithARepeatedAxis(const std::vector<AxisSample>& samples) {
  std::vector<AxisSample> out;
  for (const AxisSample& s : samples) {
    if (s.axis != 4) out.push_back(s);
  }
  for (const AxisSample& s : samples) {
    if (s.axis == 0) {
      AxisSample copy = s;
      copy.axis = 4;
      out.push_back(copy);
    }
  }
  return out;
}

bool Holds(const std::vector<int>& axes, int k) {
  return std::find(axes.begin(), axes.end(), k) != axes.end();
}

TEST(AxisSplit, BestConditionedPicksTheSubsetWithTheLargestSmallestSingularValue) {
  const auto sc = MakeOpticalAxisScenario(31);
  const std::vector<AxisSample> samples = WithARepeatedAxis(sc.samples);
  OpticalAxisOptions o;
  o.calibration_axes = 3;
  std::vector<int> cal, val;
  std::vector<std::pair<std::vector<int>, double>> candidates;
  SplitAxes(sc.nominal, samples, 5, o, &cal, &val, &candidates);
  ASSERT_EQ(candidates.size(), 10u);  // C(5, 3)
  ASSERT_EQ(cal.size(), 3u);
  ASSERT_EQ(val.size(), 2u);
  double best = 0.0, worst = 1e300, pair_best = 0.0;
  for (const auto& [axes, sigma] : candidates) {
    best = std::max(best, sigma);
    if (Holds(axes, 0) && Holds(axes, 4)) worst = std::min(worst, sigma);
    if (Holds(axes, 0) && Holds(axes, 4)) pair_best = std::max(pair_best, sigma);
  }
  for (const auto& [axes, sigma] : candidates) {
    if (axes == cal) {
      EXPECT_EQ(sigma, best);
    }
  }
  // The repeated pair is never the choice, and every subset holding it is worse than it.
  EXPECT_FALSE(Holds(cal, 0) && Holds(cal, 4));
  EXPECT_LT(pair_best, best);
  EXPECT_LE(worst, pair_best);
  for (int k = 0; k < 5; ++k) EXPECT_NE(Holds(cal, k), Holds(val, k)) << "axis " << k;
}

TEST(AxisSplit, FirstKeepsThePlanOrderAndSkipsNothing) {
  const auto sc = MakeOpticalAxisScenario(31);
  OpticalAxisOptions o;
  o.calibration_axes = 3;
  o.split = OpticalAxisOptions::Split::kFirst;
  std::vector<int> cal, val;
  std::vector<std::pair<std::vector<int>, double>> candidates;
  SplitAxes(sc.nominal, sc.samples, 5, o, &cal, &val, &candidates);
  EXPECT_EQ(cal, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(val, (std::vector<int>{3, 4}));
  EXPECT_TRUE(candidates.empty());
}

TEST(AxisSplit, IdentificationFromASingleUsableAxisIsRefused) {
  // Every axis but axis 0 lost all but two poses (as when the servo failed there): one line
  // fits any model that keeps its points collinear, so nothing is identified.
  const auto sc = MakeOpticalAxisScenario(31);
  RobotCalibration rc;
  rc.nominal = sc.nominal;
  std::vector<int> count(5, 0);
  for (const AxisSample& s : sc.samples) {
    if (s.axis == 0 || count[s.axis]++ < 2) rc.samples.push_back(s);
  }
  OpticalAxisOptions o;
  try {
    IdentifyRobot({0, 1, 2}, {3, 4}, o, &rc);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("at least 2 optical axes"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("plan axis 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twin
