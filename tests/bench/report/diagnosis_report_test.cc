#include "bench/report/diagnosis_report.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace twin {
namespace {

using json = nlohmann::json;

// A result of one accepted step and a final step without one.
DiscoveryResult TwoSteps() {
  DiscoveryResult r;
  CandidateScore c;
  c.label = "mount_deflection";
  c.accepted = true;
  DiscoveryStep s1;
  s1.index = 1;
  s1.candidates = {c};
  s1.accepted = 0;
  DiscoveryStep s2;
  s2.index = 2;
  r.steps = {s1, s2};
  return r;
}

SessionScore Score(double rms_m, double sd_m) {
  SessionScore s;
  s.points = 10;
  s.halvings = 20;
  s.rms_m = rms_m;
  s.rms_sd_m = sd_m;
  s.rms_min_m = rms_m - sd_m;
  s.rms_max_m = rms_m + sd_m;
  return s;
}

TEST(DiagnosisReport, WithoutASecondSessionItsKeysAreNull) {
  DiscoveryResult r = TwoSteps();
  r.black_box.computed = true;
  r.black_box.heldout_rms_m = 0.002;
  r.black_box.length_scale = 1.0;
  r.black_box.regularisation = 0.1;
  const json j = DiagnosisJson(r);
  for (const json& s : j["steps"]) {
    EXPECT_TRUE(s.contains("session_rms_mm"));
    EXPECT_TRUE(s["session_rms_mm"].is_null());
    EXPECT_TRUE(s["session_worse"].is_null());
  }
  EXPECT_TRUE(j.contains("session"));
  EXPECT_TRUE(j["session"].is_null());
  EXPECT_TRUE(j["black_box"]["session_rms_mm"].is_null());
  EXPECT_DOUBLE_EQ(j["black_box"]["heldout_rms_mm"].get<double>(), 2.0);
  EXPECT_EQ(j["black_box"]["in_delivered_model"], false);
}

TEST(DiagnosisReport, TheSecondSessionsScoresAreInMillimetresPerStep) {
  DiscoveryResult r = TwoSteps();
  r.session_start = Score(0.0005, 0.00001);
  r.steps[0].session = Score(0.0006, 0.00002);
  r.steps[0].session_worse = true;
  r.steps[0].session_worse_halvings = 20;
  r.steps[1].session = r.steps[0].session;
  r.session_discovered = r.steps[0].session;
  r.black_box.computed = true;
  r.black_box.session = Score(0.0003, 0.00001);
  const json j = DiagnosisJson(r);
  EXPECT_DOUBLE_EQ(j["steps"][0]["session_rms_mm"].get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(j["steps"][0]["session_rms_sd_mm"].get<double>(), 0.02);
  EXPECT_EQ(j["steps"][0]["session_worse"], true);
  EXPECT_EQ(j["steps"][0]["session_worse_halvings"], 20);
  EXPECT_EQ(j["steps"][1]["session_worse"], false);
  EXPECT_DOUBLE_EQ(j["session"]["start"]["rms_mm"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["session"]["discovered"]["rms_max_mm"].get<double>(), 0.62);
  EXPECT_DOUBLE_EQ(j["black_box"]["session_rms_mm"].get<double>(), 0.3);
}

TEST(DiagnosisReport, ABlackBoxNotComputedSaysWhy) {
  DiscoveryResult r;
  r.data = DiscoveryData::kOpticalAxes;
  r.black_box.note = "not computed for optical axes";
  const json j = DiagnosisJson(r);
  EXPECT_EQ(j["black_box"]["computed"], false);
  EXPECT_EQ(j["black_box"]["note"], "not computed for optical axes");
  EXPECT_TRUE(j["black_box"]["heldout_rms_mm"].is_null());
  EXPECT_TRUE(j["black_box"]["session_rms_mm"].is_null());
}

}  // namespace
}  // namespace twin
