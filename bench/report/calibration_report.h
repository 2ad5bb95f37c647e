// report.json of the optical-axis calibration (`twinbench run` on a scenario with a
// `calibration:` section), the calibration keys the dual-arm workflow's report shares
// (bench/report/workflow_report.h), and identification.json of `twinbench identify`. The keys
// are in docs/reference/report-json.md. Lengths in mm, angles in deg; a figure that was not
// computed (NaN, infinite, no samples) is null.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "bench/io/scenario.h"
#include "bench/report/acceptance.h"
#include "bench/scoring/calibration_results.h"

namespace twin {

/// The calibration stage's keys: scenario, intrinsics, robots.<name> (planning, servo, split,
/// misaligned_error_mm, truth_position_error_mm*, scale, unidentifiable,
/// identifiable_combinations, parameters, identification, diagnosis, declared_terms) and timing_s.
nlohmann::json CalibrationStageJson(const Scenario& scenario, const CalibrationStageResult& stage);

/// A report judged by its acceptance criteria: report.json's text (with the `acceptance` key),
/// report.html (when asked for) and the verdict.
struct JudgedReport {
  std::string json;  ///< report.json
  std::string html;  ///< report.html; empty when not asked for
  AcceptanceVerdict verdict;
};

/// Evaluates `acceptance` on `report` (EvaluateAcceptance, which adds the results) and renders
/// the texts. Throws InputError as EvaluateAcceptance.
JudgedReport JudgeReport(nlohmann::json report, const Acceptance& acceptance, bool html);

/// report.json (and report.html with `html`) of an optical-axis run: the stage's keys, judged.
JudgedReport CalibrationReport(const Scenario& scenario, const CalibrationStageResult& stage,
                               const Acceptance& acceptance, bool html);

/// identification.json of `twinbench identify`: robot, method, samples, misaligned_error_mm,
/// unidentifiable, scale and correction_mm_or_deg (the identified minus the nominal model).
std::string IdentificationReportText(const RobotCalibration& rc, const std::string& robot);

}  // namespace twin
