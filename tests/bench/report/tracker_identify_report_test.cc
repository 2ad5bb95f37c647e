#include "bench/report/tracker_identify_report.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace twin {
namespace {

using json = nlohmann::json;

TEST(TrackerIdentifyReportTest, WritesEveryKeyInReportUnits) {
  TrackerFile file;
  file.points.resize(5);
  file.joint_columns = {"q1", "q2"};
  file.ignored.push_back({"torso", 0.1, 0.1});
  file.distinct_poses = 4;
  TrackerCalibrationResult calibration;
  calibration.X_TB.translation() = Vector3(1.0, 2.0, 3.0);
  calibration.all_after = {5, 0.0002, 0.0001, 0.0004};
  IdentifiedParameter p;
  p.name = "r1.link2.a";
  p.unit = "m";
  p.start = 0.3;
  p.estimated = 0.3002;
  calibration.identified.parameters.push_back(p);
  calibration.identified.correlations.push_back({"r1.link2.a", "r1.link3.a", 0.9});
  TrackerIdentifyResult r;
  r.file = "points <1>.csv";
  r.model = "arm.yaml";
  r.robot = "r1";
  r.measurements = &file;
  r.rank_causes = {"joint 2 spans only 0.1 deg"};
  r.calibration = &calibration;
  r.declared_terms = {"backlash:1"};
  const TrackerIdentifyReport report = MakeTrackerIdentifyReport(r);
  const json j = json::parse(report.json_text);
  EXPECT_EQ(j["file"], "points <1>.csv");
  EXPECT_EQ(j["robot"], "r1");
  EXPECT_EQ(j["points"], 5);
  EXPECT_EQ(j["distinct_poses"], 4);
  EXPECT_EQ(j["columns"]["joints"], json({"q1", "q2"}));
  EXPECT_EQ(j["columns"]["ignored"][0]["name"], "torso");
  EXPECT_DOUBLE_EQ(j["all_points"]["after"]["max_mm"].get<double>(), 0.4);
  EXPECT_EQ(j["parameters"][0]["unit"], "mm");
  EXPECT_DOUBLE_EQ(j["parameters"][0]["nominal"].get<double>(), 300.0);
  // 0.2 mm; tolerance: the rounding of 300.2 - 300 in mm.
  EXPECT_NEAR(j["parameters"][0]["correction"].get<double>(), 0.2, 1e-9);
  EXPECT_EQ(j["correlations"][0]["rho"], 0.9);
  EXPECT_EQ(j["tracker_pose"]["xyz_mm"], json({1000.0, 2000.0, 3000.0}));
  EXPECT_EQ(j["tracker_pose"]["rotation_deg"], 0.0);
  EXPECT_EQ(j["declared_terms"][0], "backlash:1");
  EXPECT_EQ(j["rank_causes"][0], "joint 2 spans only 0.1 deg");
  EXPECT_EQ(j["diagnosis"]["skipped"], "--no-diagnosis");
  // Without --validate there is no second session: the key is there, null.
  EXPECT_TRUE(j["heldout"].contains("session"));
  EXPECT_TRUE(j["heldout"]["session"].is_null());
  // The file name is escaped in the page.
  EXPECT_NE(report.html.find("points &lt;1&gt;.csv"), std::string::npos) << report.html;
}

// With --validate: the nominal and geometric scores from the calibration, the discovered one
// from the diagnosis, and the diagnosis's warnings after the calibration's.
TEST(TrackerIdentifyReportTest, TheSecondSessionsScoresAndWarnings) {
  TrackerFile file;
  file.points.resize(5);
  TrackerCalibrationResult calibration;
  SessionScore s;
  s.points = 212;
  s.halvings = 20;
  s.rms_m = 0.0004;
  s.rms_sd_m = 0.00001;
  calibration.session_nominal = s;
  s.rms_m = 0.0005;
  calibration.session_geometric = s;
  calibration.warnings = {"held-out region split: WORSE"};
  DiscoveryResult diagnosis;
  s.rms_m = 0.00035;
  diagnosis.session_discovered = s;
  diagnosis.warnings = {"second session: step 2's term mount_deflection makes it WORSE"};
  TrackerIdentifyResult r;
  r.measurements = &file;
  r.calibration = &calibration;
  r.diagnosis = &diagnosis;
  const json j = json::parse(MakeTrackerIdentifyReport(r).json_text);
  const json& session = j["heldout"]["session"];
  EXPECT_EQ(session["points"], 212);
  EXPECT_EQ(session["halvings"], 20);
  EXPECT_DOUBLE_EQ(session["nominal"]["rms_mm"].get<double>(), 0.4);
  EXPECT_DOUBLE_EQ(session["geometric"]["rms_mm"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(session["discovered"]["rms_mm"].get<double>(), 0.35);
  EXPECT_DOUBLE_EQ(session["discovered"]["rms_sd_mm"].get<double>(), 0.01);
  ASSERT_EQ(j["warnings"].size(), 2u);
  EXPECT_EQ(j["warnings"][1], diagnosis.warnings[0]);
  // With --no-diagnosis the discovered score is null.
  r.diagnosis = nullptr;
  const json k = json::parse(MakeTrackerIdentifyReport(r).json_text);
  EXPECT_TRUE(k["heldout"]["session"]["discovered"].is_null());
  EXPECT_DOUBLE_EQ(k["heldout"]["session"]["nominal"]["rms_mm"].get<double>(), 0.4);
}

}  // namespace
}  // namespace twin
