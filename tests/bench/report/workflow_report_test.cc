// The dual-arm workflow report's keys (bench/report/workflow_report.h) from hand-built results:
// the stages that ran, the status and why not.
#include "bench/report/workflow_report.h"

#include <gtest/gtest.h>

namespace twin {
namespace {

using nlohmann::json;

// A handclasp stage that calibrated; its constrained estimate is delivered (no tips).
HandclaspStageResult CalibratedHandclasp(double e_tran_mm) {
  HandclaspStageResult r;
  r.status = HandclaspStageStatus::kOk;
  r.general = {true, {2 * e_tran_mm, 0.02}, {3.0, 0.2}};
  r.constrained = {true, {e_tran_mm, 0.01}, {2.0, 0.1}};
  return r;
}

TEST(WorkflowReportTest, AStoppedWorkflowReportsTheStageThatRanAndWhy) {
  WorkflowResult w;
  w.installation = BaseConstraint::kFloorWall;
  w.stage_a = CalibratedHandclasp(1.5);
  w.failure = "before the optical-axis calibration: blocked";
  Scenario sc;
  sc.name = "dual";
  const json j = WorkflowReportJson(sc, w);
  EXPECT_EQ(j["scenario"]["name"], "dual");
  EXPECT_EQ(j["status"], "failed");
  EXPECT_EQ(j["reason"], "before the optical-axis calibration: blocked");
  EXPECT_EQ(j["base_frame"]["installation"], "floor-wall");
  const json& a = j["base_frame"]["workflow"]["nominal_kinematics"];
  EXPECT_EQ(a["estimate"], "constrained");
  EXPECT_DOUBLE_EQ(a["e_tran_mm"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(a["physical_truth"]["e_tran_mm"].get<double>(), 2.0);
  EXPECT_EQ(a["stage"]["status"], "ok");
  EXPECT_FALSE(j["base_frame"]["workflow"].contains("calibrated_kinematics"));
  EXPECT_FALSE(j.contains("robots"));    // the calibration did not run
  EXPECT_FALSE(j.contains("timing_s"));  // nor its timing
}

TEST(WorkflowReportTest, ACompleteWorkflowCarriesTheCalibrationKeysAndTheCoupledMotion) {
  WorkflowResult w;
  w.stage_a = CalibratedHandclasp(1.5);
  w.calibration = CalibrationStageResult{};
  w.stage_c = CalibratedHandclasp(0.3);
  CoupledMotionResult check;
  check.ok = true;
  check.estimate = "constrained";
  check.max_deviation_mm = 0.4;
  w.stage_c->coupled_motion = check;
  w.total_s = 42.0;
  Scenario sc;
  const JudgedReport report = WorkflowReport(sc, w, Acceptance{});
  const json j = json::parse(report.json);
  EXPECT_EQ(j["status"], "ok");
  EXPECT_FALSE(j.contains("reason"));
  EXPECT_TRUE(j.contains("intrinsics"));
  EXPECT_DOUBLE_EQ(j["timing_s"]["workflow_total"].get<double>(), 42.0);
  EXPECT_DOUBLE_EQ(
      j["base_frame"]["workflow"]["calibrated_kinematics"]["e_tran_mm"].get<double>(), 0.3);
  EXPECT_EQ(j["base_frame"]["workflow"]["calibration_rough_X_B1B2"],
            "base_frame.workflow.nominal_kinematics constrained");
  EXPECT_DOUBLE_EQ(j["base_frame"]["coupled_motion"]["max_deviation_mm"].get<double>(), 0.4);
  EXPECT_FALSE(report.html.empty());  // the workflow always writes report.html
}

}  // namespace
}  // namespace twin
