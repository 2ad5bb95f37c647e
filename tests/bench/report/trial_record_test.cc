#include "bench/report/trial_record.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace twin {
namespace {

using json = nlohmann::json;

json Report() {
  return json::parse(R"({
    "scenario": {"name": "s", "seed": 3},
    "intrinsics": {"error_px": {"fx": 0.25, "cx": -1.5}, "views_used": 12},
    "robots": {"r2": {
      "planning": {"best_fitness": 2.5, "fitness_history": [[3, 2.5]], "time_s": 4.0,
                   "from_plan_store": true},
      "servo": {"aligned_poses": 12, "images": [{"file": "a.png"}], "mean_frames_per_pose": null,
                "failures": [{"axis": 1, "status": "move_failed"}]},
      "split": {"candidates": [{"calibration_axes": [0, 1]}], "rule": "best_conditioned"},
      "parameters": [{"name": "r2.link1.theta", "unit": "deg", "estimated": 0.1, "true": 0.2}],
      "identification": {"method": "ceres_with_scale", "linearized": {"eps_history_mm": [1, 2]},
                         "nonlinear": {"depth_used": true}}}},
    "timing_s": {"total": 9.5, "cell": {"frames": 40}}
  })");
}

TEST(TrialRecordTest, FlattensNumbersStringsAndTimingApart) {
  const FlatReport f = FlattenReport(Report());
  EXPECT_EQ(f.figures["intrinsics.error_px.fx"], 0.25);
  EXPECT_EQ(f.figures["intrinsics.views_used"], 12);
  EXPECT_EQ(f.figures["robots.r2.planning.best_fitness"], 2.5);
  EXPECT_EQ(f.figures["robots.r2.servo.aligned_poses"], 12);
  // Items with a name are keyed by it, others by index.
  EXPECT_EQ(f.figures["robots.r2.parameters[r2.link1.theta].estimated"], 0.1);
  EXPECT_EQ(f.figures["robots.r2.parameters[r2.link1.theta].true"], 0.2);
  EXPECT_EQ(f.figures["robots.r2.servo.failures[0].axis"], 1);
  EXPECT_EQ(f.figures["robots.r2.identification.nonlinear.depth_used"], true);
  EXPECT_EQ(f.labels["robots.r2.servo.failures[0].status"], "move_failed");
  EXPECT_EQ(f.labels["robots.r2.identification.method"], "ceres_with_scale");
  EXPECT_EQ(f.labels["robots.r2.parameters[r2.link1.theta].unit"], "deg");
  // Timing and how it ran, apart.
  EXPECT_EQ(f.timing["timing_s.total"], 9.5);
  EXPECT_EQ(f.timing["timing_s.cell.frames"], 40);
  EXPECT_EQ(f.timing["robots.r2.planning.time_s"], 4.0);
  EXPECT_EQ(f.timing["robots.r2.planning.from_plan_store"], true);
  // Left out: traces, the image list, split candidates, nulls, the scenario block.
  for (const json* part : {&f.figures, &f.labels, &f.timing}) {
    for (const auto& [key, value] : part->items()) {
      EXPECT_EQ(key.find("fitness_history"), std::string::npos) << key;
      EXPECT_EQ(key.find("eps_history"), std::string::npos) << key;
      EXPECT_EQ(key.find("images"), std::string::npos) << key;
      EXPECT_EQ(key.find("candidates"), std::string::npos) << key;
      EXPECT_EQ(key.find("mean_frames_per_pose"), std::string::npos) << key;
      EXPECT_NE(key.rfind("scenario", 0), 0u) << key;
      EXPECT_EQ(key.find("time_s") != std::string::npos || key.find("timing_s") == 0 ||
                    key.find("from_plan_store") != std::string::npos,
                part == &f.timing)
          << key;
    }
  }
}

TEST(TrialRecordTest, RecordCarriesIdentitySeedsStatusAndFigures) {
  Scenario sc;
  sc.name = "study_small";
  sc.seeds = {100, 200};
  ApplyTrial(4, &sc);
  json report = Report();
  TrialReport read;
  read.flat = FlattenReport(report);
  TrialOutcome o;
  o.status = "ok";
  o.report = &read;
  o.wall_s = 3.25;
  const TrialRecord record = MakeTrialRecord("0123456789abcdef", sc, o);
  EXPECT_EQ(record.trial(), 4);
  EXPECT_EQ(record.scenario_hash(), "0123456789abcdef");
  const json& r = record.document();
  EXPECT_EQ(r["scenario_hash"], "0123456789abcdef");
  EXPECT_EQ(r["scenario"], "study_small");
  EXPECT_EQ(r["trial"], 4);
  EXPECT_EQ(r["seeds"]["truth"], 104);
  EXPECT_EQ(r["seeds"]["estimator"], 204);
  EXPECT_FALSE(r["seeds"].contains("noise"));  // written only where the scenario sets it
  Scenario renoised;
  renoised.name = "study_small";
  renoised.seeds = {100, 200, 300};
  ApplyTrial(4, &renoised);  // every seed + 4
  EXPECT_EQ(MakeTrialRecord("0123456789abcdef", renoised, o).document()["seeds"]["noise"], 304);
  EXPECT_EQ(r["status"], "ok");
  EXPECT_EQ(r["reason"], "");
  EXPECT_EQ(r["figures"]["intrinsics.error_px.cx"], -1.5);
  EXPECT_EQ(r["run"]["wall_s"], 3.25);
  EXPECT_EQ(r["run"]["timing"]["timing_s.total"], 9.5);
  // Two runs of the same trial differ only in how they ran.
  TrialOutcome o2 = o;
  o2.wall_s = 99;
  json report2 = report;
  report2["timing_s"]["total"] = 1.0;
  report2["robots"]["r2"]["planning"]["from_plan_store"] = false;
  TrialReport read2;
  read2.flat = FlattenReport(report2);
  o2.report = &read2;
  const TrialRecord r2 = MakeTrialRecord("0123456789abcdef", sc, o2);
  EXPECT_NE(r, r2.document());
  EXPECT_EQ(ComparablePart(r), ComparablePart(r2.document()));
  EXPECT_TRUE(record.SameResultAs(r2));
  report2["intrinsics"]["error_px"]["fx"] = 0.26;
  read2.flat = FlattenReport(report2);
  EXPECT_FALSE(record.SameResultAs(MakeTrialRecord("0123456789abcdef", sc, o2)));
}

TEST(TrialRecordTest, AFailedTrialWithoutAReportKeepsItsReason) {
  Scenario sc;
  sc.name = "x";
  TrialOutcome o;
  o.status = "failed";
  o.reason = "r2 planning: no feasible pose";
  o.exit_code = 2;
  const TrialRecord record = MakeTrialRecord("h", sc, o);
  EXPECT_EQ(record.trial(), 0);
  const json& r = record.document();
  EXPECT_EQ(r["status"], "failed");
  EXPECT_EQ(r["reason"], "r2 planning: no feasible pose");
  EXPECT_EQ(r["exit_code"], 2);
  EXPECT_TRUE(r["figures"].empty());
}

// The study's reader of a trial's report.json (another process' output): the status and
// reason it reports, its flattened figures; a missing, torn or non-object file is no report.
TEST(TrialRecordTest, ReadsATrialsReportAndRefusesWhatIsNone) {
  const std::string dir = ::testing::TempDir() + "/trial_report";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/report.json";
  std::filesystem::remove(path);
  EXPECT_FALSE(ReadTrialReport(path));
  json report = Report();
  report["status"] = "failed";
  report["reason"] = "r2 servo: lost the spot";
  std::ofstream(path) << report.dump(2);
  const std::optional<TrialReport> read = ReadTrialReport(path);
  ASSERT_TRUE(read);
  EXPECT_TRUE(read->failed);
  EXPECT_EQ(read->reason, "r2 servo: lost the spot");
  EXPECT_EQ(read->flat.figures["intrinsics.error_px.fx"], 0.25);
  std::ofstream(path) << R"({"intrinsics": {"views_used": 3}})";
  const std::optional<TrialReport> ok = ReadTrialReport(path);
  ASSERT_TRUE(ok);
  EXPECT_FALSE(ok->failed);  // no status: a report of a run that went through
  EXPECT_FALSE(ok->reason);
  std::ofstream(path) << R"({"intrinsics": {"views)";  // torn
  EXPECT_FALSE(ReadTrialReport(path));
  std::ofstream(path) << "[1, 2]";
  EXPECT_FALSE(ReadTrialReport(path));
}

}  // namespace
}  // namespace twin
