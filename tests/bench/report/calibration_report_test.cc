// The optical-axis calibration report's keys (bench/report/calibration_report.h) from a
// hand-built stage result: one robot, figures in mm, null where nothing was computed.
#include "bench/report/calibration_report.h"

#include <string>

#include <gtest/gtest.h>

namespace twin {
namespace {

using nlohmann::json;

// One calibrated robot "r2" (camera on "r1"): eq. 46's error 1 mm -> 0.1 mm over 5 calibration
// samples, no validation samples; truth rigid RMS 0.2 mm after; diagnosis skipped.
CalibrationStageResult OneRobotStage() {
  CalibrationStageResult s;
  s.procedure.robots.resize(1);
  RobotCalibration& rc = s.procedure.robots[0];
  rc.calibration_error = {1e-3, 1e-4, 5};
  rc.validation_error = {0.0, 0.0, 0};
  rc.method = "nonlinear";
  s.robots.resize(1);
  RobotStageResult& r = s.robots[0];
  r.name = "r2";
  r.camera_robot = "r1";
  r.score.after.rigid.rms = 2e-4;
  r.diagnosis.skipped = "--no-diagnosis";
  r.physical_skipped = "the board is on the other robot at the end of the procedure";
  r.images.push_back({"servo_r2_axis0_before.png", "r2, axis 0"});
  s.true_intrinsics.fx = 1200.0;
  s.timing.total = 12.5;
  s.timing.frames = 30;
  return s;
}

TEST(CalibrationReportTest, TheStageKeysHoldTheFiguresInMillimetres) {
  Scenario sc;
  sc.name = "paper";
  const json j = CalibrationStageJson(sc, OneRobotStage());
  EXPECT_EQ(j["scenario"]["name"], "paper");
  EXPECT_DOUBLE_EQ(j["intrinsics"]["true"]["fx"].get<double>(), 1200.0);
  ASSERT_TRUE(j["robots"].contains("r2"));
  const json& r = j["robots"]["r2"];
  EXPECT_EQ(r["camera_robot"], "r1");
  const json& cal = r["misaligned_error_mm"]["calibration"];
  EXPECT_DOUBLE_EQ(cal["before"].get<double>(), 1.0);  // 1e-3 m
  EXPECT_DOUBLE_EQ(cal["after"].get<double>(), 0.1);
  EXPECT_NEAR(cal["decrease_percent"].get<double>(), 90.0, 1e-9);  // 1e-9: rounding of 0.9
  EXPECT_EQ(cal["samples"], 5);
  // No validation samples: every figure there, null.
  EXPECT_TRUE(r["misaligned_error_mm"]["validation"]["before"].is_null());
  EXPECT_DOUBLE_EQ(r["truth_position_error_mm"]["rigid"]["after"]["rms"].get<double>(), 0.2);
  EXPECT_TRUE(r["diagnosis"]["verdict"].is_null());
  EXPECT_EQ(r["diagnosis"]["skipped"], "--no-diagnosis");
  EXPECT_FALSE(r.contains("declared_terms"));  // only where the diagnosis ran
  EXPECT_EQ(r["truth_position_error_mm_physical"]["skipped"],
            "the board is on the other robot at the end of the procedure");
  EXPECT_EQ(r["servo"]["images"][0]["file"], "servo_r2_axis0_before.png");
  EXPECT_TRUE(r["servo"]["mean_frames_per_pose"].is_null());  // no aligned poses
  EXPECT_FALSE(r.contains("truth_position_error_mm_covered_region"));
  EXPECT_DOUBLE_EQ(j["timing_s"]["total"].get<double>(), 12.5);
  EXPECT_EQ(j["timing_s"]["cell"]["frames"], 30);
  EXPECT_TRUE(j["timing_s"]["cell"]["region_mean_pixels"].is_null());  // no region frames
}

TEST(CalibrationReportTest, TheJudgedReportIsTheJsonTextAndTheHtmlWhenAsked) {
  Scenario sc;
  sc.name = "paper";
  const JudgedReport with = CalibrationReport(sc, OneRobotStage(), Acceptance{}, true);
  EXPECT_EQ(json::parse(with.json)["robots"]["r2"]["camera_robot"], "r1");
  EXPECT_EQ(with.json.back(), '\n');
  EXPECT_NE(with.html.find("<html"), std::string::npos);
  EXPECT_TRUE(with.verdict.passed());
  EXPECT_TRUE(CalibrationReport(sc, OneRobotStage(), Acceptance{}, false).html.empty());
}

TEST(CalibrationReportTest, DecreasePercentIsNanWithoutABefore) {
  EXPECT_DOUBLE_EQ(DecreasePercent(2.0, 0.5), 75.0);
  EXPECT_TRUE(std::isnan(DecreasePercent(0.0, 0.5)));
}

}  // namespace
}  // namespace twin
