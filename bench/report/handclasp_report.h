// report.json of the handclasp base-frame calibration (`twinbench run` on a scenario with a
// `handclasp:` section alone) and the handclasp stage's section that the dual-arm workflow
// embeds (bench/report/workflow_report.h). The keys are in docs/reference/report-json.md.
// Lengths in mm, angles in deg (ZYZ Euler angles for rotations).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "bench/io/scenario.h"
#include "bench/report/acceptance.h"
#include "bench/scoring/handclasp_results.h"

namespace twin {

/// One stage's report: installation, operator_error_mm, taught_points, status (and reason),
/// truth, scoring_frame, physical_truth, pendant_tip_error, skipped, warnings, contacts, general,
/// constrained, tips_identified, coupled_motion and seed, as far as the stage got.
nlohmann::json HandclaspStageJson(const HandclaspStageResult& stage);

/// The coupled-motion check: status, estimate, and deviation_mm / max_deviation_mm or reason.
nlohmann::json CoupledMotionJson(const CoupledMotionResult& check);

/// report.json of a handclasp run: scenario (its name), procedure, status, base_frame (trial 0's
/// stage, with base_frame.batch when there are several trials) and the acceptance results
/// (EvaluateAcceptance, which `verdict` receives). Throws InputError as EvaluateAcceptance.
std::string HandclaspReportText(const Scenario& scenario, const HandclaspBatchResult& batch,
                                const Acceptance& acceptance, AcceptanceVerdict* verdict);

}  // namespace twin
