#include "bench/report/workflow_report.h"

#include "bench/report/handclasp_report.h"
#include "bench/report/scenario_json.h"

namespace twin {
namespace {
using json = nlohmann::json;

// The summary of one handclasp stage under base_frame.workflow: the delivered estimate's
// errors (eq. 33-34) on top, the whole stage report below.
json StageSummary(const HandclaspStageResult& r, const std::string& kinematics) {
  json j;
  j["kinematics"] = kinematics;
  j["status"] = r.ok() ? "ok" : "failed";
  if (r.ok()) {
    const ScoredBaseFrame& d = r.delivered();
    j["estimate"] = r.delivered_name();
    j["e_tran_mm"] = d.kinematic.e_tran_mm;
    j["e_rot_deg"] = d.kinematic.e_rot_deg;
    if (r.truth_available) {
      j["physical_truth"] = {{"e_tran_mm", d.physical.e_tran_mm},
                             {"e_rot_deg", d.physical.e_rot_deg}};
    }
  }
  j["stage"] = HandclaspStageJson(r);
  return j;
}

// base_frame.workflow: each stage that ran.
json WorkflowJson(const WorkflowResult& w) {
  json workflow;
  if (w.stage_a) workflow["nominal_kinematics"] = StageSummary(*w.stage_a, "nominal");
  if (w.calibration) {
    workflow["calibration_rough_X_B1B2"] = "base_frame.workflow.nominal_kinematics constrained";
  }
  if (w.stage_c) {
    workflow["calibrated_kinematics"] = StageSummary(*w.stage_c, "calibrated (optical-axis)");
  }
  return workflow;
}

}  // namespace

json WorkflowReportJson(const Scenario& scenario, const WorkflowResult& w) {
  json report;
  if (w.calibration) report = CalibrationStageJson(scenario, *w.calibration);
  if (w.stage_c && w.stage_c->coupled_motion) {
    report["base_frame"]["coupled_motion"] = CoupledMotionJson(*w.stage_c->coupled_motion);
  }
  if (!report.contains("scenario")) report["scenario"] = ScenarioJson(scenario);
  report["procedure"] = "dual-arm workflow: handclasp (Gan et al. 2014) with nominal "
                        "kinematics, optical-axis calibration (Zhu et al. 2019), handclasp "
                        "with calibrated kinematics";
  report["status"] = w.failure.empty() ? "ok" : "failed";
  if (!w.failure.empty()) report["reason"] = w.failure;
  report["base_frame"]["installation"] = ToString(w.installation);
  report["base_frame"]["workflow"] = WorkflowJson(w);
  if (report.contains("timing_s")) report["timing_s"]["workflow_total"] = w.total_s;
  if (w.stage_a && !w.stage_a->truth_available) {
    report["truth"] = TruthUnavailableJson(
        "the estimates alone, their errors null, the coupled-motion check skipped");
  }
  return report;
}

JudgedReport WorkflowReport(const Scenario& scenario, const WorkflowResult& workflow,
                            const Acceptance& acceptance) {
  return JudgeReport(WorkflowReportJson(scenario, workflow), acceptance, true);
}

}  // namespace twin
