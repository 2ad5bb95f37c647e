#include "bench/runs/workflow_run.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/report/acceptance.h"
#include "bench/report/report_html.h"
#include "bench/runs/handclasp_run.h"
#include "calib/common/clock.h"
#include "calib/common/errors.h"
#include "calib/procedures/handclasp_procedure.h"
#include "sim/world/mujoco_handles.h"

namespace twin {
namespace fs = std::filesystem;
namespace {


// Moves both robots back to the scenario's initial joints (the calibration's intrinsics step
// needs the board in view; a handclasp leaves the tips together anywhere). Robot 2 first, then
// robot 1; if a move is blocked (the tips or arms in each other's way), the other order.
// Returns "" or why it failed.
std::string ReturnToStart(TwinCell& cell, const Scenario& sc) {
  std::string why;
  for (const std::array<int, 2> order : {std::array<int, 2>{1, 0}, std::array<int, 2>{0, 1}}) {
    why.clear();
    for (int k : order) {
      const MoveResult m = cell.MoveTo(k, sc.twin.robots[k].q_initial);
      if (m.status != MoveStatus::kSettled) {
        why = sc.robot_names[k] + " back to its initial joints: " + m.reason;
        break;
      }
    }
    if (why.empty()) return why;
  }
  return why;
}

// The summary of one handclasp stage under base_frame.workflow: the constrained estimate's
// errors (eq. 33-34) on top, the whole stage report below.
nlohmann::json StageSummary(const HandclaspStageResult& r, const std::string& kinematics) {
  nlohmann::json j;
  j["kinematics"] = kinematics;
  j["status"] = r.ok ? "ok" : "failed";
  if (r.ok) {
    const ScoredBaseFrame& d = r.delivered();
    j["estimate"] = r.delivered_name();
    j["e_tran_mm"] = d.kinematic.e_tran_mm;
    j["e_rot_deg"] = d.kinematic.e_rot_deg;
    j["physical_truth"] = {{"e_tran_mm", d.physical.e_tran_mm},
                           {"e_rot_deg", d.physical.e_rot_deg}};
  }
  j["stage"] = r.report;
  return j;
}

}  // namespace

int RunWorkflowScenario(const RunOptions& o) {
  const auto t_start = Clock::now();
  Scenario sc = LoadScenario(o.scenario);
  ApplyTrial(o.trial, &sc);
  if (!IsPresent(sc.calibration)) {
    throw InputError(sc.path, "the dual-arm workflow needs a calibration: section");
  }
  if (!IsPresent(sc.handclasp)) {
    throw InputError(sc.path, "the dual-arm workflow needs a handclasp: section");
  }
  // Everything is parsed before the cell is built: bad input writes nothing.
  const HandclaspConfig handclasp = ParseHandclaspConfig(sc);
  if (handclasp.trials != 1) {
    throw InputError(sc.path + " scenario.handclasp.trials",
                     "the dual-arm workflow runs one trial; trials must be 1, got " +
                         std::to_string(handclasp.trials));
  }
  CalibrationConfig config = ParseCalibrationConfig(sc);
  ApplyRunOptions(o, &config);  // --no-diagnosis, --plan-cache, images
  const Acceptance acceptance = ParseAcceptance(sc);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  InstallMujocoErrorHandlers();
  TwinCell cell(sc.twin, sc.path);  // a cell that does not settle at its start is bad input

  const fs::path out(o.out_dir);
  const fs::path staging = CreateStagingDirectory(o.out_dir);
  std::ostringstream discard;
  std::ostream& progress = o.quiet ? static_cast<std::ostream&>(discard) : std::cout;
  AcceptanceVerdict verdict;
  try {
    progress << "twinbench run: dual-arm workflow, scenario " << sc.name << " (" << sc.path
             << ")\n";
    const int initial_camera_robot = cell.CameraRobot();
    nlohmann::json report;
    nlohmann::json workflow;
    std::optional<HandclaspStageResult> stage_a, stage_c;  // (a) and (c), typed

    // (a) Handclasp with the controllers' nominal kinematics.
    const std::array<KinematicModel, 2> nominal = {sc.twin.robots[0].model,
                                                   sc.twin.robots[1].model};
    progress << "[" << SecondsSince(t_start) << " s] (a) handclasp with nominal kinematics\n";
    stage_a = RunHandclaspStage(cell, sc, nominal, progress);
    const HandclaspStageResult& a = *stage_a;
    workflow["nominal_kinematics"] = StageSummary(a, "nominal");
    std::string failure;
    if (!a.ok) failure = "handclasp with nominal kinematics failed";

    // (b) Optical-axis calibration of both robots, told (a)'s constrained estimate.
    if (failure.empty()) {
      const std::string back = ReturnToStart(cell, sc);
      if (!back.empty()) failure = "before the optical-axis calibration: " + back;
    }
    std::array<KinematicModel, 2> calibrated = nominal;
    if (failure.empty()) {
      config.knowledge.X_B1B2 = a.X_B1B2_constrained;
      progress << "[" << SecondsSince(t_start)
               << " s] (b) optical-axis calibration of both robots\n";
      std::fflush(stdout);
      const OpticalAxisResult b =
          RunCalibrationStage(cell, sc, config, staging, o.quiet, t_start, &report);
      std::array<bool, 2> done = {false, false};
      for (const RobotCalibration& rc_robot : b.robots) {
        // The identified model's link 7 is the board mount; WithTipTool (in the stage) puts
        // the tip in its place, keeping X_BL0 and links 1-6 as identified.
        calibrated[rc_robot.robot] = rc_robot.identified;
        done[rc_robot.robot] = true;
      }
      if (!done[0] || !done[1]) failure = "the optical-axis calibration left a robot out";
      workflow["calibration_rough_X_B1B2"] = "base_frame.workflow.nominal_kinematics constrained";
    }

    // (c) Handclasp again with the calibrated kinematics and the small contact error; the
    // tools go back to where they started (the calibration exchanged camera and board), at
    // the start pose, where the calibration exchanged them (wherever the calibration left the
    // robots, the exchanged tools may touch something).
    if (failure.empty()) {
      const std::string back = ReturnToStart(cell, sc);
      if (!back.empty()) failure = "before the second handclasp: " + back;
    }
    if (failure.empty() && cell.CameraRobot() != initial_camera_robot) {
      const MoveResult m = cell.ExchangeTools();
      if (m.status != MoveStatus::kSettled) failure = "exchanging the tools back: " + m.reason;
    }
    if (failure.empty()) {
      progress << "[" << SecondsSince(t_start) << " s] (c) handclasp with calibrated kinematics, "
               << 1e3 * handclasp.calibrated_operator_error_m << " mm operator error\n";
      HandclaspStageOptions stage;
      stage.operator_error_m = handclasp.calibrated_operator_error_m;
      stage.identify_tips = handclasp.calibrated_tip_identification;
      stage.best_fit_frames = true;
      stage_c = RunHandclaspStage(cell, sc, calibrated, progress, stage);
      const HandclaspStageResult& c = *stage_c;
      workflow["calibrated_kinematics"] = StageSummary(c, "calibrated (optical-axis)");
      if (!c.ok) failure = "handclasp with calibrated kinematics failed";
      if (c.report.contains("coupled_motion")) {
        report["base_frame"]["coupled_motion"] = c.report["coupled_motion"];
      }
    }
    if (report.is_null() || !report.contains("scenario")) {
      report["scenario"] = ScenarioJson(sc);
    }
    report["procedure"] = "dual-arm workflow: handclasp (Gan et al. 2014) with nominal "
                          "kinematics, optical-axis calibration (Zhu et al. 2019), handclasp "
                          "with calibrated kinematics";
    report["status"] = failure.empty() ? "ok" : "failed";
    if (!failure.empty()) report["reason"] = failure;
    report["base_frame"]["installation"] = ToString(handclasp.constraint);
    report["base_frame"]["workflow"] = workflow;
    if (report.contains("timing_s")) report["timing_s"]["workflow_total"] = SecondsSince(t_start);
    if (!failure.empty()) {
      // A refused stage is exit 2 with its reason (README, exit codes); nothing is written.
      std::string detail;
      for (const std::optional<HandclaspStageResult>* stage : {&stage_c, &stage_a}) {
        if (*stage && !(*stage)->ok && !(*stage)->reason.empty()) {
          detail = ": " + (*stage)->reason;
          break;
        }
      }
      throw InputError(sc.path, "the dual-arm workflow refused: " + failure + detail);
    }
    verdict = EvaluateAcceptance(acceptance, &report);

    {
      std::ofstream f(staging / "report.json");
      f << report.dump(2) << '\n';
      if (!f) throw InputError((staging / "report.json").string(), "writing the report failed");
    }
    {
      std::ofstream f(staging / "report.html");
      f << RenderReportHtml(report);
      if (!f) throw InputError((staging / "report.html").string(), "writing the report failed");
    }
    PublishDirectory(staging.string(), out.string());

    const auto line = [&](const HandclaspStageResult& r, const char* label) {
      if (!r.ok) {
        std::printf("%-34s failed\n", label);
        return;
      }
      const ScoredBaseFrame& d = r.delivered();
      std::printf("%-34s e_tran %8.3f mm  e_rot %7.4f deg  (%s; physical %.3f mm, %.4f deg)\n",
                  label, d.kinematic.e_tran_mm, d.kinematic.e_rot_deg, r.delivered_name(),
                  d.physical.e_tran_mm, d.physical.e_rot_deg);
      if (std::isfinite(r.coupled_motion_max_deviation_mm)) {
        std::printf("%-34s coupled motion: largest tip-to-tip deviation %.3f mm\n", "",
                    r.coupled_motion_max_deviation_mm);
      }
    };
    if (!o.quiet) {
      std::printf("\nbase frame (%s installation):\n", ToString(handclasp.constraint));
      line(*stage_a, "  handclasp, nominal kinematics");
      if (stage_c) line(*stage_c, "  handclasp, calibrated kinematics");
      std::printf("wrote %s/{report.json, report.html, measurements.csv, servo_*.png}\n",
                  out.string().c_str());
    }
  } catch (const InputError& e) {
    DiscardStaging(staging.string());
    if (e.where().rfind(sc.path, 0) == 0) throw;
    throw InputError(sc.path, e.what());  // a run-time refusal names the scenario too
  } catch (...) {
    DiscardStaging(staging.string());
    throw;
  }
  if (!o.junit.empty()) WriteJunit(o.junit, sc.name, verdict, SecondsSince(t_start));
  PrintVerdict(verdict);
  return VerdictExitCode(verdict);
}

}  // namespace twin
