// The handclasp report's keys (bench/report/handclasp_report.h) from hand-built stage results:
// which keys each outcome has and their units (mm, deg).
#include "bench/report/handclasp_report.h"

#include <string>

#include <gtest/gtest.h>

namespace twin {
namespace {

using nlohmann::json;

// A stage that calibrated: the general estimate 500 mm along x, scored 0.25 mm / 0.01 deg off,
// fitted with a 0.2 mm residual; the truth 1 m along x; the coupled motion within 0.03 mm.
HandclaspStageResult CalibratedStage() {
  HandclaspStageResult r;
  r.status = HandclaspStageStatus::kOk;
  r.teaching.installation = BaseConstraint::kFloorFloor;
  r.teaching.operator_error_m = 5e-4;
  r.teaching.taught.points = 4;
  r.teaching.taught.q1.resize(4);
  r.frames.truth.translation() = Vector3(1.0, 0.0, 0.0);
  r.frames.dd1_m = {0.003, -0.002};
  r.procedure.status = HandclaspResult::Status::kSuccess;
  r.procedure.calibration.rms_residual_general_m = 2e-4;
  r.X_B1B2_general.translation() = Vector3(0.5, 0.0, 0.0);
  r.general = {true, {0.25, 0.01}, {2.5, 0.1}};
  r.constrained = {true, {0.2, 0.008}, {2.4, 0.09}};
  CoupledMotionResult check;
  check.ok = true;
  check.estimate = "constrained";
  check.deviation_mm = {0.01, 0.03};
  check.max_deviation_mm = 0.03;
  r.coupled_motion = check;
  return r;
}

TEST(HandclaspReportTest, ACalibratedStageHasItsEstimatesInMillimetresAndDegrees) {
  const json j = HandclaspStageJson(CalibratedStage());
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["installation"], "floor-floor");
  EXPECT_DOUBLE_EQ(j["operator_error_mm"].get<double>(), 0.5);  // 5e-4 m
  EXPECT_EQ(j["taught_points"]["count"], 4);
  EXPECT_EQ(j["taught_points"]["poses"], 4);
  EXPECT_DOUBLE_EQ(j["truth"]["xyz_mm"][0].get<double>(), 1000.0);
  EXPECT_DOUBLE_EQ(j["general"]["xyz_mm"][0].get<double>(), 500.0);
  EXPECT_DOUBLE_EQ(j["general"]["e_tran_mm"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(j["general"]["rms_residual_mm"].get<double>(), 0.2);  // 2e-4 m
  EXPECT_DOUBLE_EQ(j["physical_truth"]["constrained"]["e_tran_mm"].get<double>(), 2.4);
  EXPECT_DOUBLE_EQ(j["scoring_frame"]["link1_offsets"][0]["dd1_mm"].get<double>(), 3.0);
  EXPECT_EQ(j["pendant_tip_error"].size(), 2u);
  EXPECT_EQ(j["coupled_motion"]["status"], "ok");
  EXPECT_DOUBLE_EQ(j["coupled_motion"]["max_deviation_mm"].get<double>(), 0.03);
  // The tips were not asked for, and no batch seed was set.
  EXPECT_FALSE(j.contains("tips_identified"));
  EXPECT_FALSE(j.contains("seed"));
}

TEST(HandclaspReportTest, AFailedTeachingHasOnlyTheTeachingAndWhy) {
  HandclaspStageResult r;
  r.status = HandclaspStageStatus::kTeachingFailed;
  r.reason = "teaching: no reachable cube";
  const json j = HandclaspStageJson(r);
  EXPECT_EQ(j["status"], "failed");
  EXPECT_EQ(j["reason"], "teaching: no reachable cube");
  EXPECT_TRUE(j.contains("taught_points"));
  EXPECT_FALSE(j.contains("truth"));
  EXPECT_FALSE(j.contains("contacts"));
  EXPECT_FALSE(j.contains("general"));
}

TEST(HandclaspReportTest, TheRunReportHasTrialZeroAndTheBatchMeans) {
  HandclaspBatchResult batch;
  batch.trials = 2;
  for (int t = 0; t < 2; ++t) {
    batch.done.push_back(CalibratedStage());
    batch.done.back().seed = 11 + t;
  }
  batch.done[1].general.kinematic.e_tran_mm = 0.75;
  Scenario sc;
  sc.name = "hand";
  AcceptanceVerdict verdict;
  const json j = json::parse(HandclaspReportText(sc, batch, Acceptance{}, &verdict));
  EXPECT_TRUE(verdict.passed());
  EXPECT_EQ(j["scenario"], "hand");
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["base_frame"]["seed"], 11);
  const json& b = j["base_frame"]["batch"];
  EXPECT_DOUBLE_EQ(b["general"]["mean_e_tran_mm"].get<double>(), 0.5);  // (0.25 + 0.75) / 2
  EXPECT_EQ(b["trials_detail"].size(), 2u);
  EXPECT_EQ(b["trials_detail"][1]["seed"], 12);
  EXPECT_FALSE(j.contains("acceptance"));  // no criteria, no results
}

}  // namespace
}  // namespace twin
