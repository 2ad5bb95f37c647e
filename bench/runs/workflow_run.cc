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
#include "bench/report/workflow_report.h"
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
std::string ReturnToStart(BenchCell& cell, const Scenario& sc) {
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

// The workflow's parsed input: the scenario (trial applied) and its sections.
struct WorkflowInputs {
  Scenario sc;
  std::string text;  // the scenario's text (a recording keeps it)
  HandclaspConfig handclasp;
  CalibrationConfig config;  // the calibration section with the run options applied
  Acceptance acceptance;
};

// What the workflow's stages share: the cell, the scenario, where they write, how they report.
struct WorkflowContext {
  BenchCell& cell;
  const Scenario& sc;
  const HandclaspConfig& handclasp;
  const fs::path& staging;     // the staging folder of the outputs
  bool quiet;                  // --quiet
  Clock::time_point t_start;   // when the run began
  std::ostream& progress;      // progress lines (discarded when quiet)
};

// Loads the scenario, applies the trial and parses every section the workflow needs, and
// checks the output paths: bad input writes nothing.
WorkflowInputs LoadWorkflowInputs(const RunOptions& o) {
  WorkflowInputs in;
  Scenario& sc = in.sc;
  sc = LoadRunScenario(o, &in.text);
  if (!IsPresent(sc.calibration)) {
    throw InputError(sc.path, "the dual-arm workflow needs a calibration: section");
  }
  if (!IsPresent(sc.handclasp)) {
    throw InputError(sc.path, "the dual-arm workflow needs a handclasp: section");
  }
  // Everything is parsed before the cell is built: bad input writes nothing.
  in.handclasp = ParseHandclaspConfig(sc);
  if (in.handclasp.trials != 1) {
    throw InputError(sc.path + " scenario.handclasp.trials",
                     "the dual-arm workflow runs one trial; trials must be 1, got " +
                         std::to_string(in.handclasp.trials));
  }
  in.config = ParseCalibrationConfig(sc);
  ApplyRunOptions(o, &in.config);  // --no-diagnosis, --plan-cache, images
  in.acceptance = ParseAcceptance(sc);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  return in;
}

// (a) Handclasp with the controllers' nominal kinematics.
void RunNominalHandclasp(const WorkflowContext& ctx, const std::array<KinematicModel, 2>& nominal,
                         WorkflowResult* state) {
  ctx.progress << "[" << SecondsSince(ctx.t_start) << " s] (a) handclasp with nominal kinematics\n";
  state->stage_a = RunHandclaspStage(ctx.cell, ctx.sc, nominal, ctx.progress);
  const HandclaspStageResult& a = *state->stage_a;
  if (!a.ok()) state->failure = "handclasp with nominal kinematics failed";
}

// (b) Optical-axis calibration of both robots, told (a)'s constrained estimate. Returns the
// calibrated models (the nominal ones where it did not run).
std::array<KinematicModel, 2> RunOpticalAxisCalibration(
    const WorkflowContext& ctx, const std::array<KinematicModel, 2>& nominal,
    CalibrationConfig* config, WorkflowResult* state) {
  if (state->failure.empty()) {
    const std::string back = ReturnToStart(ctx.cell, ctx.sc);
    if (!back.empty()) state->failure = "before the optical-axis calibration: " + back;
  }
  std::array<KinematicModel, 2> calibrated = nominal;
  if (state->failure.empty()) {
    config->knowledge.X_B1B2 = state->stage_a->X_B1B2_constrained;
    ctx.progress << "[" << SecondsSince(ctx.t_start)
                 << " s] (b) optical-axis calibration of both robots\n";
    std::fflush(stdout);
    state->calibration =
        RunCalibrationStage(ctx.cell, ctx.sc, *config, ctx.staging, ctx.quiet, ctx.t_start);
    std::array<bool, 2> done = {false, false};
    for (const RobotCalibration& rc_robot : state->calibration->procedure.robots) {
      // The identified model's link 7 is the board mount; WithTipTool (in the stage) puts
      // the tip in its place, keeping X_BL0 and links 1-6 as identified.
      calibrated[rc_robot.robot] = rc_robot.identified;
      done[rc_robot.robot] = true;
    }
    if (!done[0] || !done[1]) state->failure = "the optical-axis calibration left a robot out";
  }
  return calibrated;
}

// (c) Handclasp again with the calibrated kinematics and the small contact error; the
// tools go back to where they started (the calibration exchanged camera and board), at
// the start pose, where the calibration exchanged them (wherever the calibration left the
// robots, the exchanged tools may touch something).
void RunCalibratedHandclasp(const WorkflowContext& ctx,
                            const std::array<KinematicModel, 2>& calibrated,
                            int initial_camera_robot, WorkflowResult* state) {
  if (state->failure.empty()) {
    const std::string back = ReturnToStart(ctx.cell, ctx.sc);
    if (!back.empty()) state->failure = "before the second handclasp: " + back;
  }
  if (state->failure.empty() && ctx.cell.CameraRobot() != initial_camera_robot) {
    const MoveResult m = ctx.cell.ExchangeTools();
    if (m.status != MoveStatus::kSettled) state->failure = "exchanging the tools back: " + m.reason;
  }
  if (state->failure.empty()) {
    ctx.progress << "[" << SecondsSince(ctx.t_start)
                 << " s] (c) handclasp with calibrated kinematics, "
                 << 1e3 * ctx.handclasp.calibrated_operator_error_m << " mm operator error\n";
    HandclaspStageOptions stage;
    stage.operator_error_m = ctx.handclasp.calibrated_operator_error_m;
    stage.identify_tips = ctx.handclasp.calibrated_tip_identification;
    stage.best_fit_frames = true;
    state->stage_c = RunHandclaspStage(ctx.cell, ctx.sc, calibrated, ctx.progress, stage);
    if (!state->stage_c->ok()) state->failure = "handclasp with calibrated kinematics failed";
  }
}

// A refused stage is exit 2 with its reason (docs/reference/exit-codes-and-safety.md); nothing is
// written.
void ThrowIfRefused(const Scenario& sc, const WorkflowResult& state) {
  if (state.failure.empty()) return;
  std::string detail;
  for (const std::optional<HandclaspStageResult>* stage : {&state.stage_c, &state.stage_a}) {
    // A stage whose procedure refused says why (a failed teaching has no detail here).
    if (*stage && (*stage)->status == HandclaspStageStatus::kProcedureFailed &&
        !(*stage)->reason.empty()) {
      detail = ": " + (*stage)->reason;
      break;
    }
  }
  throw InputError(sc.path, "the dual-arm workflow refused: " + state.failure + detail);
}

// Writes report.json and report.html into the staging folder.
void WriteWorkflowReport(const fs::path& staging, const JudgedReport& report) {
  {
    std::ofstream f(staging / "report.json");
    f << report.json;
    if (!f) throw InputError((staging / "report.json").string(), "writing the report failed");
  }
  {
    std::ofstream f(staging / "report.html");
    f << report.html;
    if (!f) throw InputError((staging / "report.html").string(), "writing the report failed");
  }
}

// One stage's line of the closing summary: its delivered estimate's errors, or "failed".
void PrintStageLine(const HandclaspStageResult& r, const char* label) {
  if (!r.ok()) {
    std::printf("%-34s failed\n", label);
    return;
  }
  if (!r.truth_available) {
    std::printf("%-34s estimated (%s; the cell offers no truth to score against)\n", label,
                r.delivered_name());
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
}

// The closing summary: both handclasp stages' errors and what was written.
void PrintWorkflowSummary(const WorkflowContext& ctx, const WorkflowResult& state,
                          const fs::path& out) {
  std::printf("\nbase frame (%s installation):\n", ToString(ctx.handclasp.constraint));
  PrintStageLine(*state.stage_a, "  handclasp, nominal kinematics");
  if (state.stage_c) PrintStageLine(*state.stage_c, "  handclasp, calibrated kinematics");
  std::printf("wrote %s/{report.json, report.html, measurements.csv, servo_*.png}\n",
              out.string().c_str());
}

// Runs stages (a) to (c), writes the report to the staging folder and publishes it to `out`.
// Returns the acceptance criteria's verdict; throws InputError when a stage refused.
AcceptanceVerdict RunWorkflow(const WorkflowContext& ctx, CalibrationConfig* config,
                              const Acceptance& acceptance, const fs::path& out) {
  ctx.progress << "twinbench run: dual-arm workflow, scenario " << ctx.sc.name << " ("
               << ctx.sc.path << ")\n";
  const int initial_camera_robot = ctx.cell.CameraRobot();
  WorkflowResult state;
  state.installation = ctx.handclasp.constraint;
  const std::array<KinematicModel, 2> nominal = {ctx.sc.twin.robots[0].model,
                                                 ctx.sc.twin.robots[1].model};
  // (a) Handclasp with the controllers' nominal kinematics.
  RunNominalHandclasp(ctx, nominal, &state);
  // (b) Optical-axis calibration of both robots, told (a)'s constrained estimate.
  const std::array<KinematicModel, 2> calibrated =
      RunOpticalAxisCalibration(ctx, nominal, config, &state);
  // (c) Handclasp again with the calibrated kinematics.
  RunCalibratedHandclasp(ctx, calibrated, initial_camera_robot, &state);
  ctx.cell.Finish();  // the last call: a recording is complete, a replay used up
  state.total_s = SecondsSince(ctx.t_start);
  // A refused stage ends the run here.
  ThrowIfRefused(ctx.sc, state);
  // The report, judged by the acceptance criteria; without truth, those on figures against it
  // are left out, and said so.
  const bool scored = state.stage_a->truth_available;
  const JudgedReport report = WorkflowReport(
      ctx.sc, state, scored ? acceptance : WithoutTruthCriteria(acceptance, ctx.quiet));
  // report.json and report.html, published with the stages' files.
  WriteWorkflowReport(ctx.staging, report);
  PublishDirectory(ctx.staging.string(), out.string());
  // The closing summary.
  if (!ctx.quiet) PrintWorkflowSummary(ctx, state, out);
  return report.verdict;
}

}  // namespace

int RunWorkflowScenario(const RunOptions& o) {
  const auto t_start = Clock::now();
  // Everything is parsed before the cell is built: bad input writes nothing.
  WorkflowInputs in = LoadWorkflowInputs(o);
  const Scenario& sc = in.sc;
  InstallMujocoErrorHandlers();
  // The cell (the twin here: one that does not settle at its start is bad input); on a cell
  // without truth, a real one, the report has the estimates alone.
  const std::unique_ptr<BenchCell> owned_cell =
      OpenBenchCell(sc.twin, sc.path, RunCellOptions(o, sc, in.text));
  BenchCell& cell = *owned_cell;

  const fs::path out(o.out_dir);
  const fs::path staging = CreateStagingDirectory(o.out_dir);
  std::ostringstream discard;
  std::ostream& progress = o.quiet ? static_cast<std::ostream&>(discard) : std::cout;
  AcceptanceVerdict verdict;
  try {
    // Stages (a) to (c), the report and the summary.
    const WorkflowContext ctx{cell, sc, in.handclasp, staging, o.quiet, t_start, progress};
    verdict = RunWorkflow(ctx, &in.config, in.acceptance, out);
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
