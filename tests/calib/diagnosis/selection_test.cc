#include "calib/diagnosis/selection.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/diagnosis/discovery_result.h"
#include "test_models.h"

namespace twin::discovery {
namespace {

// A tested candidate that every rule accepts under the default options (alpha 0.05, gain
// 5 %, correlation limit 0.99999).
CandidateScore Acceptable(const std::string& label, double gain) {
  CandidateScore c;
  c.label = label;
  c.tested = true;
  c.size_p_value = 0.001;
  c.p_value = c.p_adjusted = 0.001;
  c.gain_percent = gain;
  c.max_geometry_correlation = c.min_geometry_correlation = 0.5;
  c.geometry_correlations = {0.5};
  return c;
}

TEST(Selection, JudgeNamesEachRefusalInItsOrder) {
  const DiscoveryOptions o;
  CandidateScore c = Acceptable("a", 20.0);
  EXPECT_EQ(Judge(c, o), Refusal::kNone);
  // One direction the geometry's, the other its own: judged by its gain, not refused.
  c.geometry_correlations = {0.999999, 0.9};
  c.max_geometry_correlation = 0.999999;
  c.min_geometry_correlation = 0.9;
  EXPECT_EQ(Judge(c, o), Refusal::kNone);
  // Every direction the geometry's; the limit itself refuses (>=).
  c.geometry_correlations = {0.999999, 0.99999};
  c.min_geometry_correlation = 0.99999;
  EXPECT_EQ(Judge(c, o), Refusal::kGeometryDisguise);
  c.gain_percent = 4.9;
  EXPECT_EQ(Judge(c, o), Refusal::kGainTooSmall);
  c.p_adjusted = 0.05;
  EXPECT_EQ(Judge(c, o), Refusal::kNotSignificant);
  c.size_p_value = 0.2;
  EXPECT_EQ(Judge(c, o), Refusal::kSizeNotShown);
  c.tested = false;
  EXPECT_EQ(Judge(c, o), Refusal::kNotTested);
  c.identifiable = false;
  EXPECT_EQ(Judge(c, o), Refusal::kNotIdentifiable);
  c.applicable = false;
  EXPECT_EQ(Judge(c, o), Refusal::kNotApplicable);
  EXPECT_STREQ(ToString(Refusal::kGainTooSmall), "gain_too_small");
}

TEST(Selection, RefusalTextGivesTheDecidingFigures) {
  DiscoveryOptions o;
  CandidateScore c = Acceptable("a", 3.5);
  c.p_adjusted = 0.25;
  c.correlated_with = "r1.link2.a";
  c.max_geometry_correlation = 0.999998;
  c.min_geometry_correlation = 0.999995;
  c.geometry_correlations = {0.999998, 0.999995};
  EXPECT_EQ(RefusalText(Refusal::kNone, c, o, 4), "");
  EXPECT_EQ(RefusalText(Refusal::kNotSignificant, c, o, 4),
            "not significant: Holm-adjusted p = 0.25 >= 0.05 over 4 candidates");
  EXPECT_EQ(RefusalText(Refusal::kGainTooSmall, c, o, 4), "3.5 % < the 5 % worth a term");
  EXPECT_EQ(RefusalText(Refusal::kGeometryDisguise, c, o, 4),
            "a disguise of the geometry: each of its 2 direction(s) moves the measurements as "
            "a geometric correction does (|rho| >= 0.999995, the nearest r1.link2.a)");
  c.size_statistic = 1.5;
  c.size_dof = 2;
  c.size_p_value = 0.5;
  EXPECT_EQ(RefusalText(Refusal::kSizeNotShown, c, o, 4),
            "its size is not told from zero: Wald chi-square 1.5 on 2 dof, p = 0.5 >= 0.05");
}

TEST(Selection, TheLargestGainWithASizeIsChosenAndHolmCorrectsOverTheTested) {
  const DiscoveryOptions o;
  DiscoveryStep s;
  s.candidates = {Acceptable("small", 10.0), Acceptable("sizeless", 50.0),
                  Acceptable("large", 30.0), CandidateScore{}};
  s.candidates[1].size_p_value = 0.3;  // its size not told from zero: not eligible
  s.candidates[3].tested = false;      // not in Holm's family
  s.candidates[0].p_value = 0.01;
  s.candidates[1].p_value = 0.02;
  s.candidates[2].p_value = 0.04;
  const Selection sel = SelectLargestGain(o, &s);
  EXPECT_EQ(sel.tested, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(sel.best, 2);
  // Holm over 3: 3 * 0.01, max(0.03, 2 * 0.02), max(0.04, 1 * 0.04).
  EXPECT_DOUBLE_EQ(s.candidates[0].p_adjusted, 0.03);
  EXPECT_DOUBLE_EQ(s.candidates[1].p_adjusted, 0.04);
  EXPECT_DOUBLE_EQ(s.candidates[2].p_adjusted, 0.04);
  EXPECT_NE(s.candidates[1].note.find("its size is not told from zero"), std::string::npos);
  // The choice is accepted: nothing refuses it.
  DecideOnChoice(o, sel.tested, sel.best, "", &s);
  EXPECT_TRUE(s.candidates[2].accepted);
  EXPECT_FALSE(s.candidates[0].accepted);
  EXPECT_EQ(s.candidates[2].note.rfind("accepted: largest held-out gain (30 %)", 0), 0u)
      << s.candidates[2].note;
}

TEST(Selection, AnAcceptedTermPartlyTheGeometrysSaysWhichDirections) {
  const DiscoveryOptions o;
  DiscoveryStep s;
  s.candidates = {Acceptable("wobble", 40.0)};
  CandidateScore& c = s.candidates[0];
  c.geometry_correlations = {1.0, 0.97, 0.6};
  c.max_geometry_correlation = 1.0;
  c.min_geometry_correlation = 0.6;
  c.correlated_with = "r1.link1.theta";
  const Selection sel = SelectLargestGain(o, &s);
  DecideOnChoice(o, sel.tested, sel.best, "", &s);
  EXPECT_TRUE(c.accepted);
  EXPECT_NE(c.note.find("; 1 of its 3 directions move the measurements as the geometry does "
                        "(|rho| = 1 with r1.link1.theta)"),
            std::string::npos)
      << c.note;
}

TEST(Selection, ARefusedChoiceIsNotAcceptedAndItsNoteSaysWhy) {
  const DiscoveryOptions o;
  DiscoveryStep s;
  s.candidates = {Acceptable("only", 2.0)};
  const Selection sel = SelectLargestGain(o, &s);
  ASSERT_EQ(sel.best, 0);
  DecideOnChoice(o, sel.tested, sel.best, "", &s);
  EXPECT_FALSE(s.candidates[0].accepted);
  EXPECT_EQ(s.candidates[0].note, "largest held-out gain, but 2 % < the 5 % worth a term");
}

TEST(Selection, FoldSignFlipSumsTheLossDifferencesPerFold) {
  // Two folds; c loses to `better` by 1 in each: differences (2, 2) summed per fold, both
  // positive, so p = 1/4 (of the 4 sign assignments only (+, +) reaches the sum).
  CandidateScore c, better;
  c.heldout_loss = {2, 2, 2, 2};
  better.heldout_loss = {1, 1, 1, 1};
  const std::vector<int> region{0, 0, 1, 1};
  EXPECT_DOUBLE_EQ(FoldSignFlipP(c, better, region, 2), 0.25);
  better.heldout_loss.pop_back();
  EXPECT_THROW(FoldSignFlipP(c, better, region, 2), PreconditionError);
}

TEST(Selection, AClockDrivenLeaderGivesWayToAMeasuredDriverTheFoldsCannotTellApart) {
  const DiscoveryOptions o;
  DiscoveryStep s;
  s.candidates = {Acceptable("drift", 40.0), Acceptable("thermal", 38.0)};
  s.candidates[0].spec = {"thermal_drift", -1, {}};
  s.candidates[0].driver = TermDriver::kClockUnbounded;
  s.candidates[1].spec = {"thermal_growth", -1, {}};  // no dormant shape: the shape rule passes
  s.candidates[1].driver = TermDriver::kMeasured;
  // Per fold the leader is better in one, worse in the other: no evidence (p >= alpha).
  s.candidates[0].heldout_loss = {1.0, 1.0, 2.0, 2.0};
  s.candidates[1].heldout_loss = {1.5, 1.5, 1.5, 1.5};
  const std::vector<int> region{0, 0, 1, 1};
  const RobotModel start = MakeRobotModel(testing::ReinovoLikeModel(1));
  const SelectionContext x{o, region, 2, start};
  const int best = ChooseCandidate(x, &s);
  EXPECT_EQ(best, 1);
  EXPECT_TRUE(s.candidates[1].accepted);
  EXPECT_EQ(s.candidates[1].preferred_over, "drift");
  EXPECT_FALSE(s.candidates[0].accepted);
  // Sign-flip over the fold sums (1, -1): 3 of 4 assignments reach 0.
  EXPECT_DOUBLE_EQ(s.candidates[1].versus_leader_p_value, 0.75);
}

// Honest names: a second acceptable candidate whose held-out loss the region folds cannot tell
// from the accepted one's is named with it; one worse in every fold is not.
TEST(Selection, CandidatesTheFoldsCannotTellApartAreNamedTogether) {
  const DiscoveryOptions o;
  DiscoveryStep s;
  s.candidates = {Acceptable("lateral_compliance (joint 1)", 40.0),
                  Acceptable("joint_compliance (joint 2)", 38.0),
                  Acceptable("mount_deflection", 30.0)};
  for (CandidateScore& c : s.candidates) c.spec = {"thermal_growth", -1, {}};  // no shape
  // Five folds of two units. The second candidate is better than the first in two folds and
  // worse in three (fold sums -0.2, -0.2, +0.3, +0.3, +0.3): the sign flips reach its sum
  // often (p >= 0.05). The third is worse in every fold: p = 1/32 < 0.05.
  s.candidates[0].heldout_loss = {1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0};
  s.candidates[1].heldout_loss = {0.9, 0.9, 0.9, 0.9, 1.15, 1.15, 1.15, 1.15, 1.15, 1.15};
  s.candidates[2].heldout_loss = {1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5, 1.5};
  const std::vector<int> region{0, 0, 1, 1, 2, 2, 3, 3, 4, 4};
  const RobotModel start = MakeRobotModel(testing::ReinovoLikeModel(1));
  const SelectionContext x{o, region, 5, start};
  const int best = ChooseCandidate(x, &s);
  ASSERT_EQ(best, 0);
  EXPECT_TRUE(s.candidates[0].accepted);
  EXPECT_EQ(s.candidates[0].indistinguishable_from,
            std::vector<std::string>{"joint_compliance (joint 2)"});
  EXPECT_NE(s.candidates[1].note.find("indistinguishable on these data from the accepted "
                                      "lateral_compliance (joint 1)"),
            std::string::npos)
      << s.candidates[1].note;
  EXPECT_TRUE(s.candidates[2].indistinguishable_from.empty());
  EXPECT_EQ(s.candidates[2].note.find("indistinguishable"), std::string::npos);
  // The verdict names both.
  DiscoveryResult r;
  r.test_after.systematic = true;
  r.steps = {s};
  r.effects_added = {s.candidates[0]};
  StateSearchVerdict(1e-3, &r);
  EXPECT_NE(r.reason.find("lateral_compliance (joint 1) and joint_compliance (joint 2) are "
                          "indistinguishable on these data"),
            std::string::npos)
      << r.reason;
  EXPECT_NE(r.BriefReport().find("indistinguishable on these data from joint_compliance "
                                 "(joint 2)"),
            std::string::npos)
      << r.BriefReport();
}

// The other criterion of honest names: a candidate the folds do tell apart (worse in every
// fold, p = 1/32) but whose held-out change of the residual points the same way as the
// accepted one's (cosine 0.995 >= 0.99) is named with it; one at cosine 0.9 is not.
TEST(Selection, NearlyParallelHeldOutChangesAreNamedIndistinguishable) {
  const DiscoveryOptions o;
  DiscoveryStep s;
  s.candidates = {Acceptable("lateral_compliance (joint 1)", 40.0),
                  Acceptable("joint_compliance (joint 2)", 30.0),
                  Acceptable("mount_deflection", 30.0)};
  for (CandidateScore& c : s.candidates) c.spec = {"thermal_growth", -1, {}};  // no shape
  s.candidates[0].heldout_loss = std::vector<double>(10, 1.0);
  s.candidates[1].heldout_loss = std::vector<double>(10, 1.5);
  s.candidates[2].heldout_loss = std::vector<double>(10, 1.5);
  // Changes in the plane of two unit vectors u, v: cos(angle) with the chosen's u.
  const auto at = [](double cosine) {
    const double sine = std::sqrt(1.0 - cosine * cosine);
    return std::vector<double>{2 * cosine, 2 * sine, 0.0, 0.0};
  };
  s.candidates[0].heldout_change = {1.0, 0.0, 0.0, 0.0};
  s.candidates[1].heldout_change = at(0.995);
  s.candidates[2].heldout_change = at(0.9);
  EXPECT_NEAR(ChangeCosine(s.candidates[1], s.candidates[0]), 0.995, 1e-12);
  const std::vector<int> region{0, 0, 1, 1, 2, 2, 3, 3, 4, 4};
  const RobotModel start = MakeRobotModel(testing::ReinovoLikeModel(1));
  const SelectionContext x{o, region, 5, start};
  ASSERT_EQ(ChooseCandidate(x, &s), 0);
  EXPECT_EQ(s.candidates[0].indistinguishable_from,
            std::vector<std::string>{"joint_compliance (joint 2)"});
  EXPECT_NE(s.candidates[1].note.find("nearly parallel: cosine 0.995 >= 0.99"),
            std::string::npos)
      << s.candidates[1].note;
  EXPECT_EQ(s.candidates[2].note.find("indistinguishable"), std::string::npos);
}

}  // namespace
}  // namespace twin::discovery
