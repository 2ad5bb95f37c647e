// The laser-tracker calibration on the twin through the CLI (bench/runs/tracker_run.h), a
// reduced scenarios/tracker_reinovo.yaml: 40 poses.
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "text_edit.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

std::string Scenario(int poses, bool with_tracker) {
  std::string t = testing::ReadFile(std::string(TWIN_SOURCE_DIR) + "/scenarios/tracker_reinovo.yaml");
  for (int robot = 0; robot < 2; ++robot) {  // both robots' model paths
    t = testing::Replaced(t, "../models/", std::string(TWIN_SOURCE_DIR) + "/models/");
  }
  t = testing::Replaced(t, "    poses: 100\n", "    poses: " + std::to_string(poses) + "\n");
  if (!with_tracker) {
    const std::size_t a = t.find("  tracker:\n"), b = t.find("  tracker_calibration:\n");
    t.erase(a, b - a);
  }
  return t;
}

fs::path Folder(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / ("tracker_run_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// `twinbench run --no-diagnosis` of scenario `text`, written to dir/s.yaml, into dir/out.
testing::ProcessRun RunScenario(const fs::path& dir, const std::string& text) {
  std::ofstream(dir / "s.yaml") << text;
  return testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string(), "--no-diagnosis"}, 300);
}

// The report.json RunScenario wrote.
nlohmann::json Report(const fs::path& dir) {
  std::ifstream in(dir / "out" / "report.json");
  return nlohmann::json::parse(in);
}

// 40 poses with 0.01 mm of tracker noise: the truth RMS after the rigid gauge is well under
// the 0.03 mm of the full scenario (measured 0.005-0.006 mm with 100 poses; 40 poses give
// about sqrt(100/40) = 1.6 times that), and the identifiable combinations lie within 3 of
// their reported sigmas of the truth: all of 21 but, by chance (0.27 % each), at most one.
// The measurements.csv it writes is a tracker file that `twinbench identify` reads back.
TEST(TrackerRun, ReducedRunMeetsTheTruthTargetAndItsFileReadsBack) {
  const fs::path dir = Folder("reduced");
  const testing::ProcessRun r = RunScenario(dir, Scenario(40, true));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = Report(dir);
  EXPECT_EQ(j["tracker"]["poses"], 40);
  EXPECT_LT(j["truth_position_error_mm"]["rigid"]["after"]["rms"].get<double>(), 0.03);
  EXPECT_GT(j["truth_position_error_mm"]["rigid"]["before"]["rms"].get<double>(), 1.0);
  const int count = j["identifiable_combinations"]["count"];
  EXPECT_GE(count, 15);
  EXPECT_GE(j["identifiable_combinations"]["within_3_sigma"].get<int>(), count - 1);
  for (const char* split : {"random", "region"}) {
    EXPECT_LT(j["heldout"][split]["after"]["rms_mm"].get<double>(), 0.05) << split;
    EXPECT_FALSE(j["heldout"][split]["worse"].get<bool>()) << split;
  }
  const testing::ProcessRun back = testing::TwinbenchArgs(
      {"identify", "--model", std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r2.yaml",
       "--measurements", (dir / "out" / "measurements.csv").string(), "--no-diagnosis", "--out",
       (dir / "identified").string()},
      120);
  EXPECT_EQ(back.code, 0) << back.output;
  EXPECT_TRUE(fs::exists(dir / "identified" / "report.json"));
}

TEST(TrackerRun, ATrackerProcedureWithoutATrackerIsRefusedAndWritesNothing) {
  const fs::path dir = Folder("no_tracker");
  std::ofstream(dir / "s.yaml") << Scenario(40, false);
  const testing::ProcessRun r = testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string()}, 60);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("no tracker"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// The one-robot cell (scenarios/tracker_single_reinovo.yaml: the arm alone, no camera, board
// or second robot) with `poses` poses; its model path made absolute.
std::string SingleScenario(int poses) {
  std::string t =
      testing::ReadFile(std::string(TWIN_SOURCE_DIR) + "/scenarios/tracker_single_reinovo.yaml");
  t = testing::Replaced(t, "../models/", std::string(TWIN_SOURCE_DIR) + "/models/");
  return testing::Replaced(t, "    poses: 100\n", "    poses: " + std::to_string(poses) + "\n");
}

// End to end on real MuJoCo physics, reduced to 40 poses: the tracker procedure on the arm
// alone meets the shipped scenario's acceptance (truth RMS after the rigid gauge <= 0.03 mm;
// the two-robot cell's 40 poses give about 0.008 mm, see the reduced run above, and nothing
// differs for the robot calibrated but the absent board's payload), so `run` exits 0 and writes
// its usual files. The nominal model is off the truth by millimetres before.
TEST(TrackerRun, AOneRobotCellRunsEndToEndWithinItsAcceptance) {
  const fs::path dir = Folder("single");
  const testing::ProcessRun r = RunScenario(dir, SingleScenario(40));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = Report(dir);
  EXPECT_EQ(j["robot"], "r1");
  EXPECT_EQ(j["tracker"]["poses"], 40);
  EXPECT_LT(j["truth_position_error_mm"]["rigid"]["after"]["rms"].get<double>(), 0.03);
  EXPECT_GT(j["truth_position_error_mm"]["rigid"]["before"]["rms"].get<double>(), 1.0);
  for (const char* file : {"report.html", "measurements.csv", "identified_r1.yaml"}) {
    EXPECT_TRUE(fs::exists(dir / "out" / file)) << file;
  }
}

// The other verbs on a one-robot cell work or refuse with exit 2 and a reason: check passes,
// render writes overviews only (no hand camera), benchmark-twin and benchmark-planning (hand
// camera, optical-axis planning) refuse.
TEST(TrackerRun, AOneRobotCellIsCheckedRenderedOrRefusedCleanlyByTheOtherVerbs) {
  const fs::path dir = Folder("single_verbs");
  const std::string scenario = (dir / "s.yaml").string();
  std::ofstream(scenario) << SingleScenario(40);
  const testing::ProcessRun check = testing::TwinbenchArgs({"check", scenario}, 60);
  EXPECT_EQ(check.code, 0) << check.output;
  EXPECT_NE(check.output.find("the laser-tracker calibration"), std::string::npos)
      << check.output;
  const testing::ProcessRun render = testing::TwinbenchArgs(
      {"render", scenario, "--out", (dir / "render").string(), "--poses", "2"}, 120);
  EXPECT_EQ(render.code, 0) << render.output;
  EXPECT_TRUE(fs::exists(dir / "render" / "overview_00.png")) << render.output;
  EXPECT_FALSE(fs::exists(dir / "render" / "hand_camera_00.png"));
  const testing::ProcessRun bench =
      testing::TwinbenchArgs({"benchmark-twin", scenario, "--frames", "1", "--moves", "2"}, 60);
  EXPECT_EQ(bench.code, 2) << bench.output;
  EXPECT_NE(bench.output.find("no camera"), std::string::npos) << bench.output;
  const testing::ProcessRun plan = testing::TwinbenchArgs({"benchmark-planning", scenario}, 60);
  EXPECT_EQ(plan.code, 2) << plan.output;
  EXPECT_NE(plan.output.find("scenario.calibration"), std::string::npos) << plan.output;
}

// Model discovery on the twin (issue 15), reduced: 60 poses of the discovery scenarios and four
// candidates (the truth's compliant joint 2 among them). Undeclared, discovery must name the
// compliance at joint 2, and the discovered model must come close to the physical truth (the
// reflector where the twin's physics puts it): within 0.03 mm rigid RMS (the effect-free
// calibration gives about 0.011 mm with 100 poses: tracker and encoder noise), when the
// geometric model is off by about 0.6 mm. Declared, the term is in the model from the start:
// the report lists it, and discovery cannot add it again.
std::string DiscoveryScenario(const std::string& name,
                              const std::string& candidates = "joint_compliance:2, "
                                                              "joint_compliance:3, "
                                                              "transmission_error:1:1, backlash:3",
                              int poses = 60) {
  std::string t = testing::ReadFile(std::string(TWIN_SOURCE_DIR) + "/scenarios/discovery/" + name);
  for (int robot = 0; robot < 2; ++robot) {
    t = testing::Replaced(t, "../../models/", std::string(TWIN_SOURCE_DIR) + "/models/");
  }
  t = testing::Replaced(t, "    poses: 100\n", "    poses: " + std::to_string(poses) + "\n");
  t = testing::Replaced(t, "    holdout: 0.2\n",
                        "    holdout: 0.2\n    diagnosis:\n      candidates: [" + candidates +
                            "]\n");
  return t;
}

TEST(TrackerRun, BadDiagnosisSettingsAreRefusedByCheckNamingTheKey) {
  const fs::path dir = Folder("discovery_bad");
  const std::string good = DiscoveryScenario("tracker_compliance_j2.yaml");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"joint_compliance:2, ", "joint_compliance:9, "},  // no joint 9
      {"joint_compliance:2, ", "no_such_term, "},
      {"      candidates:", "      folds: 1\n      candidates:"},
      {"      candidates:", "      colour: red\n      candidates:"},
  };
  for (const auto& [from, to] : cases) {
    std::ofstream(dir / "s.yaml") << testing::Replaced(good, from, to);
    const testing::ProcessRun r = testing::TwinbenchArgs({"check", (dir / "s.yaml").string()}, 60);
    EXPECT_EQ(r.code, 2) << to << "\n" << r.output;
    EXPECT_NE(r.output.find("diagnosis"), std::string::npos) << to << "\n" << r.output;
  }
}

TEST(TrackerRun, AnUndeclaredCompliantJointIsDiscoveredAndScoredAgainstThePhysicalTruth) {
  const fs::path dir = Folder("discovery_undeclared");
  std::ofstream(dir / "s.yaml") << DiscoveryScenario("tracker_compliance_j2.yaml");
  const testing::ProcessRun r = testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string(), "--quiet"}, 600);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_TRUE(j["declared_terms"].empty());
  const nlohmann::json& d = j["diagnosis"];
  ASSERT_EQ(d["verdict"], "effects_added") << d["reason"];
  ASSERT_EQ(d["effects_added"].size(), 1u) << d["effects_added"].dump(1);
  EXPECT_EQ(d["effects_added"][0]["term"], "joint_compliance");
  EXPECT_EQ(d["effects_added"][0]["joint"], 2);
  const double calibrated = j["truth_position_error_mm_physical"]["calibrated_model"]["rigid"]["rms"];
  const double discovered = j["truth_position_error_mm_discovered_model"]["rigid"]["rms"];
  EXPECT_GT(calibrated, 0.2);
  EXPECT_LT(discovered, 0.03);
}

TEST(TrackerRun, ADeclaredEffectIsInTheModelFromTheStartAndNotDiscoveredAgain) {
  const fs::path dir = Folder("discovery_declared");
  std::ofstream(dir / "s.yaml") << DiscoveryScenario("tracker_compliance_j2_declared.yaml");
  const testing::ProcessRun r = testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string(), "--quiet"}, 600);
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["declared_terms"], nlohmann::json::array({"joint_compliance (joint 2)"}));
  for (const auto& e : j["diagnosis"]["effects_added"]) {
    EXPECT_NE(e["label"], "joint_compliance (joint 2)");
  }
  // With the term from the start, the calibrated model itself meets the physical truth.
  EXPECT_LT(j["truth_position_error_mm_physical"]["calibrated_model"]["rigid"]["rms"].get<double>(),
            0.03);
}

// An arm warming up over the session (the twin's thermal_drift, undeclared: its links grow by
// about 2e-4 over the ~14 min of the scenario's 100 poses, an exponential approach) is named
// as a time-dependent thermal term among candidates of other kinds. Scored on the
// session's own held-out regions it comes within 0.03 mm (the effect-free figure is about
// 0.021 mm: tracker noise of 3 coordinates); on the physical truth, measured after the
// session, it must still beat the geometric model (a linear drift extrapolates the
// exponential badly: docs/explanation/discovery-statistics.md). Declared, the term is there from
// the start: the estimator's warm-up, whose time constant is estimated.
TEST(TrackerRun, AnArmWarmingUpIsDiscoveredAsThermalDriftOrDeclared) {
  const fs::path dir = Folder("discovery_thermal");
  const std::string text = DiscoveryScenario(
      "tracker_thermal_drift.yaml",
      "joint_compliance:2, transmission_error:1:1, thermal_drift, thermal_warmup::10, "
      "thermal_warmup::40",
      100);
  std::ofstream(dir / "s.yaml") << text;
  const testing::ProcessRun r = testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string(), "--quiet"}, 600);
  ASSERT_EQ(r.code, 0) << r.output;
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  const nlohmann::json& d = j["diagnosis"];
  ASSERT_EQ(d["verdict"], "effects_added") << d.dump(1);
  ASSERT_EQ(d["effects_added"].size(), 1u) << d["effects_added"].dump(1);
  // Either time-dependent thermal term: the linear drift or a warm-up of some time constant.
  const std::string term = d["effects_added"][0]["term"];
  EXPECT_EQ(term.rfind("thermal_", 0), 0u) << term;
  EXPECT_NE(term, "thermal_growth");  // needs temperatures, which this procedure lacks
  // The report says what drives each candidate: the two time-dependent terms run on the clock.
  EXPECT_EQ(d["effects_added"][0]["driver"],
            term == "thermal_drift" ? "clock_unbounded" : "clock_levelling");
  for (const auto& c : d["candidates"]) {
    if (c["term"] == "joint_compliance") {
      EXPECT_EQ(c["driver"], "measured") << c.dump();
    }
  }
  EXPECT_TRUE(d["effects_added"][0]["joint"].is_null());
  EXPECT_LT(d["heldout_rms_mm"]["discovered"].get<double>(), 0.03);
  EXPECT_LT(d["heldout_rms_mm"]["discovered"].get<double>(),
            0.6 * d["heldout_rms_mm"]["start"].get<double>());
  const double calibrated = j["truth_position_error_mm_physical"]["calibrated_model"]["rigid"]["rms"];
  const double discovered = j["truth_position_error_mm_discovered_model"]["rigid"]["rms"];
  EXPECT_LT(discovered, calibrated) << "the drift term should help after the session too";

  std::ofstream(dir / "s.yaml") << testing::Replaced(text, "declared: false", "declared: true");
  const testing::ProcessRun declared = testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string(), "--quiet"}, 600);
  ASSERT_EQ(declared.code, 0) << declared.output;
  j = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  // Declared, the twin's warm-up is the estimator's warm-up (by type), its time constant
  // estimated from the declared start (a sigma: not held there), and nothing is added.
  EXPECT_EQ(j["declared_terms"],
            nlohmann::json::array({"thermal_warmup (time constant 20 min)"}));
  ASSERT_EQ(j["declared_term_parameters"].size(), 2u) << j["declared_term_parameters"].dump();
  EXPECT_EQ(j["declared_term_parameters"][1]["name"], "r2.thermal.warmup_log_tau_ratio");
  EXPECT_GT(j["declared_term_parameters"][1]["sigma"].get<double>(), 0.0);
  EXPECT_TRUE(j["diagnosis"]["effects_added"].empty()) << j["diagnosis"].dump(1);
  EXPECT_LT(j["diagnosis"]["heldout_rms_mm"]["start"].get<double>(), 0.03);
  // And it helps after the session, as the discovered term does.
  EXPECT_LT(j["truth_position_error_mm_physical"]["calibrated_model"]["rigid"]["rms"].get<double>(),
            calibrated);
}

// The same warming arm with a temperature sensor on it (robots[1].temperature_sensor): the
// points carry the sensor's change since the first point (measurements.csv's
// temperature_delta_K), and the thermal growth in kelvin is named among the time-dependent
// terms; the physical-truth poses after the session are scored at their own readings, so
// nothing is extrapolated in time.
TEST(TrackerRun, AWarmingArmWithATemperatureSensorIsDiscoveredAsThermalGrowth) {
  const fs::path dir = Folder("discovery_thermal_sensed");
  const std::string text = DiscoveryScenario(
      "tracker_thermal_drift_sensed.yaml",
      "joint_compliance:2, thermal_drift, thermal_warmup::10, thermal_growth", 100);
  std::ofstream(dir / "s.yaml") << text;
  const testing::ProcessRun r = testing::TwinbenchArgs(
      {"run", (dir / "s.yaml").string(), "--out", (dir / "out").string(), "--quiet"}, 600);
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "out" / "report.json"));
  // The sensor reads the cold arm at first: 21 deg C, noise 0.1 K (5 sigma).
  EXPECT_NEAR(j["tracker"]["temperature_reference_C"].get<double>(), 21.0, 0.5);
  const std::string csv = testing::ReadFile((dir / "out" / "measurements.csv").string());
  EXPECT_NE(csv.substr(0, csv.find('\n')).find(",temperature_delta_K"), std::string::npos);
  const nlohmann::json& d = j["diagnosis"];
  ASSERT_EQ(d["verdict"], "effects_added") << d.dump(1);
  ASSERT_EQ(d["effects_added"].size(), 1u) << d["effects_added"].dump(1);
  EXPECT_EQ(d["effects_added"][0]["term"], "thermal_growth");
  EXPECT_EQ(d["effects_added"][0]["driver"], "measured");
  // The aluminium's 2.3e-5 /K within 10 % (its sigma is about 6e-7 /K: 4 sigma). While the
  // estimator's term also grew the reflector's bracket (the tool link), which the twin does
  // not, it came out 3-11 % low in the 11 of 20 trials of the study that chose it (README.md of
  // e5af83d).
  EXPECT_NEAR(d["effects_added"][0]["parameters"][0]["estimated"].get<double>(), 2.3e-5,
              0.1 * 2.3e-5);
  const double calibrated = j["truth_position_error_mm_physical"]["calibrated_model"]["rigid"]["rms"];
  const double discovered = j["truth_position_error_mm_discovered_model"]["rigid"]["rms"];
  // The effect-free calibration of these seeds is at 0.011 mm (tracker_clean.yaml, trial 0):
  // 0.015 mm is within 1.4 times it, where the geometric model is at about 0.07 mm.
  EXPECT_LT(discovered, 0.015);
  EXPECT_GT(calibrated, 3.0 * discovered);
}

}  // namespace
}  // namespace twin
