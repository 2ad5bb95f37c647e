// The dual-arm workflow (bench/workflow_run.h): dispatch from `twinbench run`, input errors
// (exit 2, nothing written), and a reduced run whose report carries both stages.
#include "tests/bench/cli_run.h"
#include "bench/workflow_run.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calib/errors.h"
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
