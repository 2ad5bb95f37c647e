// report.json of the dual-arm workflow (bench/runs/workflow_run.h): the calibration stage's keys
// (bench/report/calibration_report.h) plus procedure, status, reason and base_frame
// (installation, workflow.{nominal_kinematics, calibration_rough_X_B1B2,
// calibrated_kinematics}, coupled_motion) and timing_s.workflow_total.
#pragma once

#include <nlohmann/json.hpp>

#include "bench/io/scenario.h"
#include "bench/report/calibration_report.h"
#include "bench/scoring/workflow_results.h"

namespace twin {

/// The report before the acceptance criteria are judged on it.
nlohmann::json WorkflowReportJson(const Scenario& scenario, const WorkflowResult& workflow);

/// report.json and report.html of the workflow, judged by `acceptance` (JudgeReport).
JudgedReport WorkflowReport(const Scenario& scenario, const WorkflowResult& workflow,
                            const Acceptance& acceptance);

}  // namespace twin
