#include "bench/report/tracker_report.h"

#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace twin {
namespace {

using json = nlohmann::json;

IdentifiedParameter Parameter(const std::string& name, const std::string& unit, double estimated,
                              double sigma) {
  IdentifiedParameter p;
  p.name = name;
  p.unit = unit;
  p.estimated = estimated;
  p.sigma = sigma;
  return p;
}

// A small hand-built result: two geometric parameters, one declared term's, one combination,
// one held-out split that got worse, the physical truth with a discovered model.
struct Fixture {
  Scenario sc;
  TrackerProcedureResult procedure;
  TrackerRunResult result;

  Fixture() {
    sc.name = "tracker_small";
    procedure.points.resize(3);
    procedure.attempts = 4;
    procedure.skipped.push_back({2, "unreachable"});
    HeldOutSplit split;
    split.name = "random";
    split.rule = "every 5th";
    split.training = 2;
    split.before = {1, 0.002, 0.002, 0.002};
    split.after = {1, 0.003, 0.003, 0.003};
    split.worse = true;
    procedure.calibration.splits.push_back(split);
    IdentificationResult& id = procedure.calibration.identified;
    id.parameters = {Parameter("r2.link1.theta", "rad", 0.01, 0.001),
                     Parameter("r2.link1.d", "m", 0.4005, 0.0001),
                     Parameter("r2.joint_compliance.2", "rad/(N m)", 1e-5, 1e-6)};
    id.z = Eigen::VectorXd::Constant(1, 0.5);
    id.observability.rank = 1;
    id.observability.singular_values = {2.0};
    id.observability.unidentifiable = {"r2.link6.theta"};
    id.sigma0 = 1.1;
    procedure.calibration.warnings = {"held-out random: worse"};
    result.scenario = &sc;
    result.robot = "r2";
    result.procedure = &procedure;
    result.declared_terms = {"joint_compliance:2"};
    result.notes = {"a note"};
    result.tracker_sigma_m = 1e-5;
    result.truth.before.raw = {0.004, 0.008};
    result.truth.after.raw = {0.0001, 0.0003};
    result.truth.phi0 = Eigen::Vector2d(0.0, 0.4);
    result.truth.phi_true = Eigen::Vector2d(0.012, 0.4004);
    result.truth.within3 = 1;
    result.truth.combinations.push_back({0, 0.5, 0.52, 0.01, true});
    result.physical.poses = 7;
    result.physical.calibrated.rigid = {0.0002, 0.0005};
    result.physical.discovered = GaugeErrors{};
    result.physical.discovered->rigid = {0.0001, 0.0002};
    result.diagnosis_skipped = "--no-diagnosis";
    result.total_s = 2.5;
  }
};

TEST(TrackerReportTest, WritesEveryKeyInReportUnits) {
  const Fixture f;
  const TrackerReport report = MakeTrackerReport(f.result, Acceptance{});
  const json j = json::parse(report.json_text);
  EXPECT_EQ(j["scenario"]["name"], "tracker_small");
  EXPECT_EQ(j["robot"], "r2");
  EXPECT_EQ(j["tracker"]["poses"], 3);
  EXPECT_EQ(j["tracker"]["attempts"], 4);
  EXPECT_DOUBLE_EQ(j["tracker"]["sigma_mm"].get<double>(), 0.01);  // 1e-5 m
  EXPECT_TRUE(j["tracker"]["temperature_reference_C"].is_null());  // no sensor: NaN
  EXPECT_EQ(j["tracker"]["skipped"][0]["reason"], "unreachable");
  EXPECT_DOUBLE_EQ(j["heldout"]["random"]["after"]["rms_mm"].get<double>(), 3.0);
  EXPECT_EQ(j["heldout"]["random"]["worse"], true);
  EXPECT_DOUBLE_EQ(j["truth_position_error_mm"]["raw"]["before"]["rms"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(j["truth_position_error_mm"]["raw"]["after"]["max"].get<double>(), 0.3);
  // Deviations from nominal in deg and mm; the declared term's parameter as identified.
  ASSERT_EQ(j["parameters"].size(), 2u);
  EXPECT_EQ(j["parameters"][0]["unit"], "deg");
  // 0.01 rad and 0.012 rad in deg; tolerance: the rad-to-deg product's rounding.
  EXPECT_NEAR(j["parameters"][0]["estimated"].get<double>(), 0.572958, 1e-6);
  EXPECT_NEAR(j["parameters"][0]["true"].get<double>(), 0.687549, 1e-6);
  EXPECT_EQ(j["parameters"][1]["unit"], "mm");
  // 0.5 mm from 0.4005 - 0.4 m; tolerance: the subtraction's rounding at 0.4 m.
  EXPECT_NEAR(j["parameters"][1]["estimated"].get<double>(), 0.5, 1e-9);
  ASSERT_EQ(j["declared_term_parameters"].size(), 1u);
  EXPECT_EQ(j["declared_term_parameters"][0]["name"], "r2.joint_compliance.2");
  EXPECT_EQ(j["identifiable_combinations"]["count"], 1);
  EXPECT_EQ(j["identifiable_combinations"]["items"][0]["true"], 0.52);
  EXPECT_EQ(j["unidentifiable"][0], "r2.link6.theta");
  EXPECT_EQ(j["condition_number"], 1.0);
  EXPECT_EQ(j["declared_terms"][0], "joint_compliance:2");
  EXPECT_EQ(j["truth_position_error_mm_physical"]["poses"], 7);
  EXPECT_DOUBLE_EQ(
      j["truth_position_error_mm_physical"]["discovered_model"]["rigid"]["rms"].get<double>(), 0.1);
  EXPECT_EQ(j["truth_position_error_mm_discovered_model"],
            j["truth_position_error_mm_physical"]["discovered_model"]);
  EXPECT_TRUE(j["diagnosis"]["verdict"].is_null());
  EXPECT_EQ(j["diagnosis"]["skipped"], "--no-diagnosis");
  EXPECT_EQ(j["warnings"], json({"held-out random: worse", "a note"}));
  EXPECT_EQ(j["timing_s"]["total"], 2.5);
  EXPECT_TRUE(report.verdict.passed());
  EXPECT_NE(report.html.find("WORSE"), std::string::npos);
  EXPECT_NE(report.html.find("tracker_small"), std::string::npos);
}

TEST(TrackerReportTest, NoPhysicalTruthWithoutReachedPoses) {
  Fixture f;
  f.result.physical = TrackerPhysicalTruthScores{};
  const json j = json::parse(MakeTrackerReport(f.result, Acceptance{}).json_text);
  EXPECT_FALSE(j.contains("truth_position_error_mm_physical"));
  EXPECT_FALSE(j.contains("truth_position_error_mm_discovered_model"));
}

}  // namespace
}  // namespace twin
