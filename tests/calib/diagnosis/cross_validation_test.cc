#include "calib/diagnosis/cross_validation.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "stub_discovery_data.h"

namespace twin::discovery {
namespace {

using stub::StubData;


TEST(CrossValidation, EveryUnitIsPredictedOnceByAFitThatNeverSawIt) {
  const StubData data(5);
  const RobotModel model;
  // Folds 0 {0, 2}, 1 {1, 3}, 2 {4}; fold 3 is empty and skipped but counts in the means.
  const CrossValidation cv = CrossValidate(data, model, {0, 1, 0, 1, 2}, 4, "test");
  ASSERT_EQ(cv.e.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(cv.e[i].size(), 1) << i;  // filled: held out once
    EXPECT_EQ(cv.e[i](0), 0.0) << i;    // by a fit without it
  }
  EXPECT_EQ(cv.dof, 5.0);
  EXPECT_DOUBLE_EQ(cv.unknowns, 3 * 2.0 / 4);          // 3 fits of 2 unknowns over 4 folds
  EXPECT_DOUBLE_EQ(cv.train_rows, (3 + 3 + 4) / 4.0);  // training units of the 3 fits
  EXPECT_DOUBLE_EQ(cv.Sse(), 1 + 2 + 3 + 4 + 5);
  EXPECT_DOUBLE_EQ(cv.Rms(), 2.0);
  EXPECT_THROW(CrossValidate(data, model, {0, 1}, 2, "test"), PreconditionError);
}

TEST(CrossValidation, TheResidualTestDividesOutTheInflationAndComparesWithChiSquare) {
  CrossValidation cv;
  cv.Resize(2);
  cv.chi2 = {2.0, 3.0};
  cv.dof = 2;
  cv.unknowns = 2;
  cv.train_rows = 8;
  const DiscoveryOptions o;  // alpha 0.05
  ResidualTest t = TestResiduals(cv, o, "rule");
  EXPECT_EQ(t.held_out, "rule");
  EXPECT_EQ(t.points, 2);
  EXPECT_DOUBLE_EQ(t.inflation, 1.25);  // 1 + 2 / 8
  EXPECT_DOUBLE_EQ(t.statistic, 4.0);   // 5 / 1.25
  // Chi-square with 2 dof has the tail exp(-x / 2); 1e-12: the tail's own accuracy.
  EXPECT_NEAR(t.p_value, std::exp(-2.0), 1e-12);
  EXPECT_FALSE(t.systematic);  // 0.135 >= 0.05
  cv.chi2 = {5.0, 5.0};
  t = TestResiduals(cv, o, "rule");
  EXPECT_NEAR(t.p_value, std::exp(-4.0), 1e-12);
  EXPECT_TRUE(t.systematic);  // 0.018 < 0.05
  cv.dof = 0;
  EXPECT_THROW(TestResiduals(cv, o, "rule"), PreconditionError);
}

TEST(CrossValidation, AResidualTestWithoutDegreesOfFreedomIsBadInput) {
  const RobotModel model;
  const DiscoveryOptions o;
  // The global test of data with no redundancy: the user's data are too few.
  EXPECT_THROW(RunResidualTest(StubData(4, true), model, {}, 2, o, "rule", "test"), InputError);
  // Held out: one dof a unit.
  const ResidualTest t = RunResidualTest(StubData(4), model, {0, 1, 0, 1}, 2, o, "rule", "test");
  EXPECT_EQ(t.dof, 4.0);
}

TEST(CrossValidation, AnInSampleTestOfDataWithoutOneIsABug) {
  // Data's default InSample: only data with a global test may be asked for one.
  class NoGlobal : public StubData {
   public:
    NoGlobal() : StubData(3) {}
    CrossValidation InSample(const RobotModel& m, const std::string& w) const override {
      return Data::InSample(m, w);
    }
  };
  EXPECT_THROW(NoGlobal().InSample(RobotModel(), "test"), PreconditionError);
}

}  // namespace
}  // namespace twin::discovery
