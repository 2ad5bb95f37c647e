#include "calib/diagnosis/discovery_result.h"

#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace twin {
namespace {

TEST(DiscoveryResult, VerdictsAndDataKindsHaveTheReportsWords) {
  EXPECT_STREQ(ToString(DiscoveryVerdict::kConsistentWithNoise), "consistent_with_noise");
  EXPECT_STREQ(ToString(DiscoveryVerdict::kEffectsAdded), "effects_added");
  EXPECT_STREQ(ToString(DiscoveryVerdict::kUnexplained), "unexplained");
  EXPECT_STREQ(ToString(DiscoveryData::kTrackerPoints), "tracker_points");
  EXPECT_STREQ(ToString(DiscoveryData::kOpticalAxes), "optical_axes");
}

// A search that added one effect, by hand.
DiscoveryResult OneEffect() {
  DiscoveryResult r;
  r.test_before.rms_m = 0.5e-3;
  r.test_before.p_value = 1e-6;
  r.test_before.systematic = true;
  r.test_after.p_value = 0.4;
  r.noise.sigma_m = 1e-5;
  r.noise.source = "stated";
  r.heldout_rms_start_m = 0.5e-3;
  DiscoveryStep s;
  s.heldout_rms_before_m = 0.5e-3;
  s.heldout_rms_after_m = 0.02e-3;
  CandidateScore c;
  c.label = "compliance q2";
  c.tested = true;
  c.gain_percent = 99.5;
  c.p_adjusted = 1e-5;
  c.accepted = true;
  s.candidates = {c};
  s.accepted = 0;
  r.steps = {s};
  r.effects_added = {c};
  return r;
}

TEST(DiscoveryResult, TheSearchVerdictAndItsReason) {
  DiscoveryResult r = OneEffect();
  discovery::StateSearchVerdict(0.02e-3, &r);
  EXPECT_EQ(r.verdict, DiscoveryVerdict::kEffectsAdded);
  EXPECT_EQ(r.reason,
            "1 effect(s) added; region-disjoint held-out RMS 0.5 mm -> 0.02 mm; the residual is "
            "then consistent with noise (p = 0.4)");
  // The same step with a residual still systematic after it: partly explained.
  DiscoveryResult partly = OneEffect();
  partly.test_after.systematic = true;
  partly.test_after.p_value = 1e-6;
  discovery::StateSearchVerdict(0.02e-3, &partly);
  EXPECT_EQ(partly.verdict, DiscoveryVerdict::kPartlyExplained);
  EXPECT_STREQ(ToString(partly.verdict), "partly_explained");
  EXPECT_NE(partly.reason.find("still systematic (p = 1e-06)"), std::string::npos) << partly.reason;
  r.effects_added.clear();
  discovery::StateSearchVerdict(0.5e-3, &r);
  EXPECT_EQ(r.verdict, DiscoveryVerdict::kUnexplained);
  EXPECT_EQ(r.test_after.p_value, r.test_before.p_value);  // nothing added: the start's test
}

TEST(DiscoveryResult, TheHidingPlacesAreTheCandidatesWhoseDetectionLimitIsAboveTheStatedMultiple) {
  // Noise floor 0.01 mm, could_hide_noise_multiple 3: room above 0.03 mm at the end point.
  DiscoveryResult r = OneEffect();
  r.effects_added.clear();
  discovery::StateSearchVerdict(0.5e-3, &r);
  ASSERT_EQ(r.verdict, DiscoveryVerdict::kUnexplained);
  DiscoveryOptions o;
  o.could_hide_noise_multiple = 3.0;
  const auto candidate = [](const std::string& label, double limit_m) {
    CandidateScore c;
    c.label = label;
    c.detection_limit_m = limit_m;
    return c;
  };
  const std::vector<CandidateScore> candidates{
      candidate("not computed", std::numeric_limits<double>::quiet_NaN()),
      candidate("seen", 0.02e-3),                  // below 0.03 mm: the test would find it
      candidate("roomy", 0.05e-3),                 // above
      candidate("roomier", 0.08e-3),               // above, larger: named first
      candidate("blind", std::numeric_limits<double>::infinity())};  // first of all
  const std::string before = r.reason;
  discovery::AddHidingPlaces(o, candidates, "the last step's candidates", &r);
  EXPECT_EQ(r.could_hide, (std::vector<std::string>{"blind", "roomier", "roomy"}));
  EXPECT_EQ(r.reason,
            before + "; an effect of 3 of the last step's candidates could be there unseen, "
                     "moving the end point by more than 0.03 mm RMS (3 x the noise floor's "
                     "sigma; the size a test finds with 80 % power): blind (unidentifiable: "
                     "blind to a combination that moves the end point), roomier (up to 0.08 mm), "
                     "roomy (up to 0.05 mm)");
  // None above the limit: nothing named, the reason unchanged.
  DiscoveryResult quiet = OneEffect();
  discovery::AddHidingPlaces(o, {candidate("seen", 0.02e-3)}, "", &quiet);
  EXPECT_TRUE(quiet.could_hide.empty());
  EXPECT_EQ(quiet.reason, OneEffect().reason);
}

TEST(DiscoveryResult, BriefReportHasTheVerdictNoiseTestAndOneLineAStep) {
  DiscoveryResult r = OneEffect();
  discovery::StateSearchVerdict(0.02e-3, &r);
  EXPECT_EQ(r.BriefReport(),
            "diagnosis: effects_added: " + r.reason +
                "\n"
                "  noise floor 0.0100 mm per coordinate (stated)\n"
                "  residual test (held out): RMS 0.5000 mm, p = 1e-06 (systematic)\n"
                "  step 1: 1 of 1 candidates tested; best compliance q2, held-out gain 99.5 %, "
                "Holm p = 1e-05: ACCEPTED; region held-out RMS 0.5000 mm -> 0.0200 mm\n");
  const std::string full = r.FullReport();
  EXPECT_EQ(full.rfind(r.BriefReport(), 0), 0u);
  EXPECT_NE(full.find("    compliance q2: held-out RMS"), std::string::npos) << full;
  EXPECT_NE(full.find("[accepted]"), std::string::npos) << full;
}

}  // namespace
}  // namespace twin
