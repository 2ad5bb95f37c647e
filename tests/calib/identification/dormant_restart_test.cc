#include "calib/identification/dormant_restart.h"

#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "test_models.h"

namespace twin {
namespace {

// A fit that is its IdentificationResult, as the rule requires of a caller's fit.
struct StubFit {
  IdentificationResult result;
};

// A stub whose first fit (of the start) and restart have the given rank and cost; each call
// is recorded. The models are told apart by their term values (one value: 0 start, 1
// restart).
struct Stub {
  int first_rank = 10, again_rank = 11;
  double first_cost = 2.0, again_cost = 1.0;
  std::vector<bool> calls;  // the `restart` argument of each fit
  StubFit operator()(const RobotModel& m, bool restart) {
    calls.push_back(restart);
    StubFit f;
    const bool is_restart = m.term_values.size() == 1 && m.term_values(0) == 1.0;
    f.result.observability.rank = is_restart ? again_rank : first_rank;
    f.result.cost_after = is_restart ? again_cost : first_cost;
    f.result.model = m;
    return f;
  }
};

RobotModel Marked(double v) {
  RobotModel m;
  m.term_values = Eigen::VectorXd::Constant(1, v);
  return m;
}

DormantRestart<StubFit> FitStub(Stub* stub, bool wake) {
  const auto fit = [stub](const RobotModel& m, bool restart) { return (*stub)(m, restart); };
  const auto woken = [wake](const RobotModel&,
                            const IdentificationResult&) -> std::optional<RobotModel> {
    if (!wake) return std::nullopt;
    return Marked(1.0);
  };
  return FitWithDormantRestart<StubFit>(Marked(0.0), fit, woken);
}

TEST(DormantRestart, NothingAsleepIsFittedOnce) {
  Stub stub;
  const DormantRestart<StubFit> r = FitStub(&stub, false);
  EXPECT_EQ(stub.calls, std::vector<bool>{false});
  EXPECT_FALSE(r.restarted);
  EXPECT_EQ(r.model.term_values(0), 0.0);
}

TEST(DormantRestart, ARestartThatIdentifiesMoreAndCostsNoMoreIsKept) {
  Stub stub;  // rank 10 -> 11, cost 2 -> 1
  const DormantRestart<StubFit> r = FitStub(&stub, true);
  EXPECT_EQ(stub.calls, (std::vector<bool>{false, true}));
  EXPECT_TRUE(r.restarted);
  EXPECT_EQ(r.model.term_values(0), 1.0);
  EXPECT_EQ(r.fit.result.observability.rank, 11);
}

TEST(DormantRestart, NoWorseIsTheCostWithinItsSlack) {
  Stub within;
  within.again_cost = 2.0 * (1.0 + 0.5 * kRestartCostSlack);  // worse by half the slack
  EXPECT_TRUE(FitStub(&within, true).restarted);
  Stub beyond;
  beyond.again_cost = 2.0 * (1.0 + 2.0 * kRestartCostSlack);  // worse by twice the slack
  const DormantRestart<StubFit> r = FitStub(&beyond, true);
  EXPECT_FALSE(r.restarted);
  EXPECT_EQ(r.model.term_values(0), 0.0);
  EXPECT_EQ(r.fit.result.cost_after, 2.0);  // the first fit is kept with its start
}

TEST(DormantRestart, ARestartThatIdentifiesNoMoreIsNotKeptHoweverCheap) {
  Stub stub;
  stub.again_rank = 10;
  stub.again_cost = 0.5;
  EXPECT_FALSE(FitStub(&stub, true).restarted);
}

TEST(DormantRestart, DeclaredTermsWakeOnlyWhereADormantTermSleepsAtZero) {
  const KinematicModel chain = testing::ReinovoLikeModel(1);
  const RobotModel geometric = MakeRobotModel(chain);
  IdentificationResult first;
  first.model = geometric;
  EXPECT_FALSE(WithDormantTermsWoken(geometric, first).has_value());
  // A warm-up at zero: its values come from the first solution.
  const RobotModel start =
      WithTerm(geometric, MakeErrorTerm({"thermal_warmup", -1, {40}}, chain, chain.name));
  ASSERT_TRUE(HasDormantTermsAtZero(start));
  first.model = start;
  first.model.term_values.setConstant(0.25);
  const std::optional<RobotModel> woken = WithDormantTermsWoken(start, first);
  ASSERT_TRUE(woken.has_value());
  EXPECT_EQ(woken->term_values, first.model.term_values);
}

}  // namespace
}  // namespace twin
