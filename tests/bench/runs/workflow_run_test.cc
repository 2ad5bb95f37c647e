// The dual-arm workflow (bench/runs/workflow_run.h): dispatch from `twinbench run`, input errors
// (exit 2, nothing written), and a reduced run whose report carries both stages.
#include "tests/bench/cli_run.h"
#include "bench/runs/workflow_run.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calib/common/errors.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {

using twin::testing::ReadFile;
using twin::testing::Replaced;

const std::string kScenarioDir = std::string(TWIN_SOURCE_DIR) + "/scenarios/";

using twin::testing::CliRun;
using twin::testing::Twinbench;

// workflow_dual.yaml with absolute model paths, edited by `edit`, written to a temp file.
std::string WriteScenario(const std::string& file, std::string text) {
  for (const std::string m : {"reinovo_r1.yaml", "reinovo_r2.yaml"}) {
    text = Replaced(text, "../models/" + m, std::string(TWIN_SOURCE_DIR) + "/models/" + m);
  }
  const std::string path = ::testing::TempDir() + "/" + file;
  std::ofstream(path) << text;
  return path;
}

std::string Workflow() { return ReadFile(kScenarioDir + "workflow_dual.yaml"); }

TEST(WorkflowRun, BadHandclaspKeyIsExit2AndWritesNothing) {
  const std::string scenario = WriteScenario(
      "wf_bad_key.yaml", Replaced(Workflow(), "calibrated_operator_error_mm: 0.1",
                                  "calibrated_operator_error_mm: -0.1"));
  const std::string out = ::testing::TempDir() + "/wf_bad_key_out";
  std::filesystem::remove_all(out);
  const CliRun r = Twinbench("run " + scenario + " --out " + out);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("scenario.handclasp.calibrated_operator_error_mm"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find(">= 0 mm"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

TEST(WorkflowRun, MoreThanOneTrialIsExit2) {
  const std::string scenario =
      WriteScenario("wf_trials.yaml", Replaced(Workflow(), "trials: 1", "trials: 3"));
  const std::string out = ::testing::TempDir() + "/wf_trials_out";
  std::filesystem::remove_all(out);
  const CliRun r = Twinbench("run " + scenario + " --out " + out);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("scenario.handclasp.trials"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("trials must be 1, got 3"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(WorkflowRun, BadCalibrationKeyIsExit2) {
  // The calibration section is parsed before anything runs, as without the handclasp.
  const std::string scenario = WriteScenario(
      "wf_bad_cal.yaml", Replaced(Workflow(), "intrinsics_views: 40", "intrinsics_viewz: 40"));
  const CliRun r = Twinbench("run " + scenario + " --out " + ::testing::TempDir() + "/wf_x");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("intrinsics_viewz"), std::string::npos) << r.output;
}

TEST(WorkflowRun, RefusesAScenarioWithoutBothSections) {
  const std::string scenario =
      WriteScenario("wf_no_handclasp.yaml", ReadFile(kScenarioDir + "paper_reinovo.yaml"));
  RunOptions o;
  o.scenario = scenario;
  o.out_dir = ::testing::TempDir() + "/wf_no_handclasp_out";
  o.quiet = true;
  try {
    RunWorkflowScenario(o);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("needs a handclasp: section"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twin

namespace twin {
namespace {

TEST(WorkflowRun, AReducedRunReportsBothStagesAndTheCalibratedOneIsBetter) {
  // The whole workflow on the real twin with a small calibration (12 intrinsics views, 4 axes
  // x 5 positions planned by a short PSO, 3 calibrating): both handclasp stages, the
  // optical-axis calibration of both robots and the tip identification run end to end.
  // The scenario's acceptance section is the full run's target, not this reduced one's.
  std::string s = Workflow();
  s = s.substr(0, s.find("  # The CI verdict"));
  s = Replaced(s, "intrinsics_views: 40", "intrinsics_views: 12");
  s = Replaced(s, "axes: 5", "axes: 4");
  s = Replaced(s, "positions_per_axis: 10", "positions_per_axis: 5");
  s = Replaced(s, "swarm_size: 10", "swarm_size: 6");
  s = Replaced(s, "iterations: 100", "iterations: 10");
  s = Replaced(s, "runs: 5", "runs: 1");
  const std::string path = WriteScenario("wf_reduced.yaml", s);
  const std::string out = ::testing::TempDir() + "/wf_reduced_out";
  std::filesystem::remove_all(out);
  // --no-diagnosis reaches the workflow's calibration stage (and keeps this test short).
  const CliRun r = Twinbench("run " + path + " --out " + out + " --no-diagnosis");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(out + "/report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* robot : {"r1", "r2"}) {
    EXPECT_EQ(j["robots"][robot]["diagnosis"]["skipped"], "--no-diagnosis")
        << j["robots"][robot]["diagnosis"].dump();
  }
  const nlohmann::json& w = j["base_frame"]["workflow"];
  const double nominal = w["nominal_kinematics"]["e_tran_mm"].get<double>();
  const double calibrated = w["calibrated_kinematics"]["e_tran_mm"].get<double>();
  std::printf("[ measured ] reduced workflow: e_tran nominal %.3f mm -> calibrated %.3f mm, "
              "e_rot %.4f -> %.4f deg\n",
              nominal, calibrated, w["nominal_kinematics"]["e_rot_deg"].get<double>(),
              w["calibrated_kinematics"]["e_rot_deg"].get<double>());
  EXPECT_EQ(w["calibrated_kinematics"]["estimate"], "tips_identified") << w.dump(1);
  // Nominal kinematics of 2 mm / 0.25 deg errors put the handclasp several millimetres off;
  // even this small calibration must at least halve it.
  EXPECT_GT(nominal, 2.0);
  EXPECT_LT(calibrated, 0.5 * nominal);
  // The physical check, frame-free: robot 2 following robot 1 through the estimate (with the
  // identified tips) deviates at most half as much as with the nominal kinematics.
  const nlohmann::json& cm = w["calibrated_kinematics"]["stage"]["coupled_motion"];
  const nlohmann::json& cm0 = w["nominal_kinematics"]["stage"]["coupled_motion"];
  ASSERT_EQ(cm["status"], "ok") << cm.dump();
  ASSERT_EQ(cm0["status"], "ok") << cm0.dump();
  std::printf("[ measured ] coupled motion: nominal %.3f mm, calibrated %.3f mm\n",
              cm0["max_deviation_mm"].get<double>(), cm["max_deviation_mm"].get<double>());
  EXPECT_LT(cm["max_deviation_mm"].get<double>(), 0.5 * cm0["max_deviation_mm"].get<double>());
  for (const char* key : {"report.json", "report.html", "measurements.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(out + "/" + key)) << key;
  }
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

}  // namespace
}  // namespace twin
