#include "calib/diagnosis/candidate_scoring.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "stub_discovery_data.h"
#include "test_models.h"

namespace twin::discovery {
namespace {

using stub::StubData;

const TermSpec kCompliance2{"joint_compliance", 1, {}};
const TermSpec kThermalGrowth{"thermal_growth", -1, {}};

RobotModel Start() { return MakeRobotModel(twin::testing::ReinovoLikeModel(1)); }

// A context of the start's 6 joints, without time or temperature.
MeasurementContext Joints() {
  MeasurementContext c;
  c.q = JointVector::Zero(6);
  return c;
}

TEST(CandidateScoring, ATermWithoutItsContextOrThatCannotBeMadeIsNotApplicable) {
  const StubData data(3, false, Joints());
  const RobotModel base = Start();
  RobotModel model;
  CandidateScore c;
  c.label = "thermal growth";
  // The data has no temperatures.
  EXPECT_FALSE(BuildCandidateModel(data, base, kThermalGrowth, &model, &c));
  EXPECT_FALSE(c.applicable);
  EXPECT_EQ(c.note.rfind("not applicable: ", 0), 0u) << c.note;
  EXPECT_NE(c.note.find("(unit 0)"), std::string::npos) << c.note;
  // No such term.
  CandidateScore d;
  EXPECT_FALSE(BuildCandidateModel(data, base, {"no_such_term", -1, {}}, &model, &d));
  EXPECT_FALSE(d.applicable);
  // A compliance needs the joint readings only: the base with one more term.
  CandidateScore e;
  ASSERT_TRUE(BuildCandidateModel(data, base, kCompliance2, &model, &e));
  EXPECT_TRUE(e.applicable);
  EXPECT_EQ(model.terms.size(), base.terms.size() + 1);
}

TEST(CandidateScoring, TheRankDecidesIdentifiableWholeOrPartly) {
  const StubData data(3);
  CandidateFit f;
  f.added = 3;
  CandidateScore none, part, whole;
  f.rank = 30;  // base rank 30: no rise
  EXPECT_FALSE(RaisesRank(data, f, 30, &none));
  EXPECT_FALSE(none.identifiable);
  EXPECT_EQ(none.note.rfind("unidentifiable from stub data", 0), 0u) << none.note;
  f.rank = 31;
  EXPECT_TRUE(RaisesRank(data, f, 30, &part));
  EXPECT_EQ(part.note, "partly identifiable: the rank rises by 1 of its 3 parameters");
  f.rank = 33;
  EXPECT_TRUE(RaisesRank(data, f, 30, &whole));
  EXPECT_TRUE(whole.identifiable);
  EXPECT_TRUE(whole.note.empty()) << whole.note;
}

TEST(CandidateScoring, TheSizeTestIsWaldsChiSquareOfTheAmplitude) {
  const RobotModel base = Start();
  const auto term = MakeErrorTerm(kCompliance2, base.chain, base.name());
  ASSERT_EQ(term->parameters().size(), 1u);
  // Estimate 3e-5 with sigma 1e-5: W = 9 on 1 dof, p = erfc(sqrt(9 / 2)).
  IdentificationResult fit;
  fit.parameters.resize(2);
  fit.parameters[1].estimated = 3e-5;
  fit.covariance = Eigen::MatrixXd::Zero(2, 2);
  fit.covariance(1, 1) = 1e-10;
  CandidateScore c;
  SizeTest(fit, 1, *term, std::nan(""), &c);
  // 1e-9 relative: Wald's pseudo-inverse of a 1 x 1 covariance, and the tail's accuracy.
  EXPECT_NEAR(c.size_statistic, 9.0, 1e-9 * 9.0);
  EXPECT_EQ(c.size_dof, 1);
  EXPECT_NEAR(c.size_p_value, std::erfc(std::sqrt(4.5)), 1e-12);
}

TEST(CandidateScoring, TheHeldOutGainIsTheReductionOfTheBasesLoss) {
  const StubData data(20);
  std::vector<int> folds_of(20);
  for (int i = 0; i < 20; ++i) folds_of[i] = i % 2;
  // The stub's held-out loss of unit i is 1 + i, whatever the model: a base of twice that
  // loses half of its sum of squares to the candidate, on every unit.
  CrossValidation base;
  base.Resize(20);
  for (int i = 0; i < 20; ++i) base.loss[i] = 2.0 * (1 + i);
  CandidateScore c;
  TestHeldOut(data, RobotModel(), folds_of, 2, base, &c);
  EXPECT_TRUE(c.tested);
  EXPECT_DOUBLE_EQ(c.gain_percent, 50.0);
  EXPECT_DOUBLE_EQ(c.heldout_rms_m, 2.0);  // sqrt of the stub's squared distance 4
  ASSERT_EQ(c.heldout_loss.size(), 20u);
  EXPECT_EQ(c.heldout_loss[3], 4.0);
  // 20 positive differences of distinct size: Wilcoxon's W+ is the largest, p far below 1 %.
  EXPECT_LT(c.p_value, 0.01);
}

TEST(CandidateScoring, ARefusalOfTheDataIsACandidatesOutcomeAndAnyOtherErrorABug) {
  StubData data(3, false, Joints());
  data.fit = [](const RobotModel&, const std::string& what) -> Fit {
    throw InputError("stub (" + what + ")", "the identification failed: singular");
  };
  const RobotModel base = Start();
  const CrossValidation base_cv;
  std::vector<std::string> lines;
  const auto say = [&](const std::string& line) { lines.push_back(line); };
  const std::vector<CandidateScore> out =
      ScoreAll(data, base, 30, {kCompliance2, kThermalGrowth}, {0, 1, 0}, 2, base_cv, true, 0.05, 2,
               say, "step 1");
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].label, TermLabel(kCompliance2));  // in the order of the specs
  EXPECT_FALSE(out[0].identifiable);
  EXPECT_EQ(out[0].note.rfind("its identification failed: stub (candidate ", 0), 0u)
      << out[0].note;
  EXPECT_FALSE(out[1].applicable);  // no temperatures: never fitted
  EXPECT_EQ(lines.size(), 2u);
  data.fit = [](const RobotModel&, const std::string&) -> Fit {
    throw std::logic_error("a bug");
  };
  EXPECT_THROW(ScoreAll(data, base, 30, {kCompliance2}, {0, 1, 0}, 2, base_cv, true, 0.05, 1, say,
                        "step 1"),
               std::logic_error);
  EXPECT_THROW(ScoreAll(data, base, 30, {kCompliance2}, {0, 1, 0}, 2, base_cv, true, 0.05, 0, say,
                        "step 1"),
               PreconditionError);
}

}  // namespace
}  // namespace twin::discovery
