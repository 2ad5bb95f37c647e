// Typed results of the dual-arm workflow (bench/runs/workflow_run.h): its three stages as far
// as they ran. bench/report/workflow_report.h writes them as report.json.
#pragma once

#include <optional>
#include <string>

#include "bench/scoring/calibration_results.h"
#include "bench/scoring/handclasp_results.h"

namespace twin {

/// The workflow's stages, scored.
struct WorkflowResult {
  BaseConstraint installation = BaseConstraint::kGeneral;  ///< the handclasp's constraint
  std::optional<HandclaspStageResult> stage_a;  ///< (a) handclasp, nominal kinematics
  std::optional<CalibrationStageResult> calibration;  ///< (b) optical-axis calibration
  std::optional<HandclaspStageResult> stage_c;  ///< (c) handclasp, calibrated kinematics
  std::string failure;  ///< why the workflow stopped; empty when every stage ran
  double total_s = 0;   ///< the workflow's wall time until its report [s]
};

}  // namespace twin
