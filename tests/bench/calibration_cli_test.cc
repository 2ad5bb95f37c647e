// `twinbench run` input errors and `twinbench identify` on recorded measurements: exit 2 with
// the bad input named and nothing written; a synthetic recording identifies exactly.
#include "tests/bench/cli_run.h"
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../calib/optical_axis_synthetic.h"
#include "bench/io/csv.h"
#include "bench/io/model_yaml.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

using twin::testing::CliRun;
using twin::testing::Twinbench;

fs::path TempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("twinbench_calib_cli_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

const std::string kScenarios = std::string(TWIN_SOURCE_DIR) + "/scenarios/";

TEST(CalibrationCli, ScenarioWithoutCalibrationSectionExitsTwoAndWritesNothing) {
  const fs::path dir = TempDir("nocal");
  const CliRun r = Twinbench("run " + kScenarios + "twin_demo.yaml --out " + (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("scenario.calibration"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "out.partial"));
}

TEST(CalibrationCli, UnknownCalibrationKeyNamesFileLineAndKey) {
  const fs::path dir = TempDir("badkey");
  // Scenario paths are relative to the file: point the models back at the source tree.
  std::ofstream(dir / "bad.yaml") << testing::Replaced(
      testing::AbsoluteModels(testing::ReadFile(kScenarios + "paper_reinovo.yaml")),
      "servo: {tolerance_px: 0.1,", "servo: {tolerance_pix: 0.1,");
  const CliRun r = Twinbench("run " + (dir / "bad.yaml").string() + " --out " +
                             (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.yaml:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("tolerance_pix"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// The reduced study scenario (4 axes x 5 positions, a few seconds): the diagnosis runs by
// default on the calibrated robot's aligned poses and its verdict, noise floor (each sample's
// own, from the board pose) and the physical-truth scoring are in the report; --no-diagnosis
// skips it and says so.
TEST(CalibrationCli, RunDiagnosesEachCalibratedRobotUnlessTold) {
  const fs::path dir = TempDir("diagnosis");
  const CliRun r = Twinbench("run " + kScenarios + "study_small.yaml --quiet --out " +
                             (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "out" / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  const nlohmann::json& d = j["robots"]["r2"]["diagnosis"];
  ASSERT_TRUE(d["verdict"].is_string()) << d.dump();
  const std::string verdict = d["verdict"];
  EXPECT_TRUE(verdict == "consistent_with_noise" || verdict == "effects_added" ||
              verdict == "partly_explained" || verdict == "unexplained")
      << verdict;
  EXPECT_EQ(d["data"], "optical_axes");
  EXPECT_NE(d["noise_floor"]["source"].get<std::string>().find("each sample's own"),
            std::string::npos)
      << d["noise_floor"].dump();
  EXPECT_GT(d["noise_floor"]["depth_sigma_mm"].get<double>(), 0.0);
  // Screened candidates exactly when nothing was searched
  // (docs/explanation/discovery-statistics.md).
  ASSERT_TRUE(d["screened"].is_array()) << d.dump();
  EXPECT_EQ(d["screened"].empty(), verdict != "consistent_with_noise") << verdict;
  for (const nlohmann::json& c : d["screened"]) {
    EXPECT_FALSE(c["tested"].get<bool>()) << c.dump();
    EXPECT_FALSE(c["accepted"].get<bool>()) << c.dump();
  }
  EXPECT_TRUE(j["robots"]["r2"]["truth_position_error_mm_physical"].contains("poses"))
      << j["robots"]["r2"]["truth_position_error_mm_physical"].dump();
  // The same inside the joint box of the aligned poses: at least the 10 poses a gauge needs,
  // both models scored.
  const nlohmann::json& covered = j["robots"]["r2"]["truth_position_error_mm_physical_covered_region"];
  ASSERT_TRUE(covered.contains("poses")) << j["robots"]["r2"].dump();
  EXPECT_GE(covered["poses"].get<int>(), 10);
  EXPECT_GT(covered["calibrated_model"]["rigid"]["rms"].get<double>(), 0.0);
  EXPECT_GT(covered["discovered_model"]["rigid"]["rms"].get<double>(), 0.0);
  EXPECT_NE(r.output.find("diagnosis"), std::string::npos) << r.output;

  const CliRun skip = Twinbench("run " + kScenarios + "study_small.yaml --quiet --no-diagnosis "
                                "--out " + (dir / "skip").string());
  ASSERT_EQ(skip.code, 0) << skip.output;
  std::ifstream in2(dir / "skip" / "report.json");
  const nlohmann::json k = nlohmann::json::parse(in2);
  EXPECT_TRUE(k["robots"]["r2"]["diagnosis"]["verdict"].is_null());
  EXPECT_EQ(k["robots"]["r2"]["diagnosis"]["skipped"], "--no-diagnosis");
}

// The reduced scenario with a temperature sensor on r2 (21 deg C cold, 0.1 K per reading) and
// r2 warming up fast (30 K, 5 min: some 4 K over the session): every aligned pose records the
// clock and the reading less the first pose's, and report.json the first reading. The twin's
// warming at each row's clock, 30 (1 - exp(-t / 300 s)) K, is what the sensor must read to
// within its noise: 0.7 K is 5 sigma of a difference of two readings (0.14 K).
TEST(CalibrationCli, ATemperatureSensorIsReadAtEveryAlignedPose) {
  const fs::path dir = TempDir("temperature");
  std::string text = testing::AbsoluteModels(testing::ReadFile(kScenarios + "study_small.yaml"));
  text = testing::Replaced(text, "      initial_joints_deg: [11.86, 21.16, -15.50, -64.86, 76.88, -25.73]\n",
                           "      initial_joints_deg: [11.86, 21.16, -15.50, -64.86, 76.88, -25.73]\n"
                           "      temperature_sensor: {ambient_C: 21.0, sigma_K: 0.1}\n");
  text = testing::Replaced(text, "  effects:\n",
                           "  effects:\n    - {type: thermal_drift, declared: false, robot: r2, coefficient_per_K: "
                           "2.3e-5, delta_T_K: 30, time_constant_s: 300}\n");
  std::ofstream(dir / "scenario.yaml") << text;
  const CliRun r = Twinbench("run " + (dir / "scenario.yaml").string() +
                             " --quiet --no-diagnosis --no-images --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto warming = [](double t) { return -30.0 * std::expm1(-t / 300.0); };
  std::ifstream in(dir / "out" / "measurements.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const std::vector<std::string> header = SplitCsv(line);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  };
  const int time_col = column("time_s"), temp_col = column("temperature_delta_K");
  ASSERT_GE(time_col, 0);
  ASSERT_GE(temp_col, 0);
  int rows = 0;
  double t_first = 0;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = SplitCsv(line);
    ASSERT_EQ(f.size(), header.size()) << "row " << rows + 1;
    const double t = CsvNumber(f[time_col], "time_s");
    const double delta = CsvNumber(f[temp_col], "temperature_delta_K");
    if (rows == 0) {
      t_first = t;
      EXPECT_EQ(delta, 0.0);  // the reference is the first reading itself
    }
    EXPECT_GE(t, t_first) << "row " << rows + 1;
    EXPECT_NEAR(delta, warming(t) - warming(t_first), 0.7) << "row " << rows + 1 << ", t " << t;
    ++rows;
  }
  EXPECT_GE(rows, 10);
  std::ifstream rj(dir / "out" / "report.json");
  const nlohmann::json j = nlohmann::json::parse(rj);
  ASSERT_TRUE(j["robots"]["r2"].contains("temperature_reference_C")) << j["robots"]["r2"].dump();
  // 21 deg C plus the warming at the first pose, to 5 sigma of one reading.
  EXPECT_NEAR(j["robots"]["r2"]["temperature_reference_C"].get<double>(),
              21.0 + warming(t_first), 0.5);
}

TEST(CalibrationCli, BadDiagnosisSettingsAndBoardMassNameFileLineAndKey) {
  const fs::path dir = TempDir("baddiag");
  const std::string yaml = testing::AbsoluteModels(testing::ReadFile(kScenarios + "study_small.yaml"));
  const std::string anchor = "    calibration_axes: 3\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"    diagnosis: {alpha: 0.9}\n", "alpha"},
      {"    diagnosis: {candidates: [joint_compliance:9]}\n", "candidates"},
      {"    diagnosis: {depth_sigma_mm: -1}\n", "depth_sigma_mm"},
      {"    diagnosis: {folds: 5, foldz: 3}\n", "foldz"},
      {"    diagnosis: {screen: often}\n", "screen"},
      {"    board_mass_kg: 500\n", "board_mass_kg"},
      {"    intrinsics_distortion: fisheye\n", "intrinsics_distortion"},
      {"    intrinsics_target: {squares: [13, 10], square_mm: 20}\n", "intrinsics_target"},
      {"    intrinsics_target: {squares: [14, 10]}\n", "square_mm"},
      {"    intrinsics_target: {squares: [14, 10], square_mm: 20, size: 3}\n", "size"}};
  for (const auto& [insert, key] : cases) {
    std::ofstream(dir / "bad.yaml") << testing::Replaced(yaml, anchor, anchor + insert);
    const CliRun r = Twinbench("run " + (dir / "bad.yaml").string() + " --out " +
                               (dir / "out").string());
    EXPECT_EQ(r.code, 2) << insert << r.output;
    EXPECT_NE(r.output.find("bad.yaml:"), std::string::npos) << insert << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << insert << r.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << insert;
  }
}

// Told of an intrinsics target the cell does not have: the run stops at the intrinsics step
// with the reason (the cell's refusal), exit 2, and writes nothing.
TEST(CalibrationCli, AToldIntrinsicsTargetTheCellLacksStopsTheRunAndWritesNothing) {
  const fs::path dir = TempDir("notarget");
  const std::string yaml = testing::AbsoluteModels(testing::ReadFile(kScenarios + "study_small.yaml"));
  const std::string anchor = "    calibration_axes: 3\n";
  std::ofstream(dir / "s.yaml") << testing::Replaced(
      yaml, anchor, anchor + "    intrinsics_target: {squares: [14, 10], square_mm: 20}\n");
  const CliRun r = Twinbench("run " + (dir / "s.yaml").string() + " --quiet --out " +
                             (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("cannot mount the intrinsics_target"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no intrinsics target"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir / "out.partial"));
}

// A recording as `twinbench run` writes it, from the synthetic optical-axis data: exact joint
// angles, depths from the axis' camera point, zero offsets; axes 0-2 calibration, 3-4 validation.
std::string SyntheticCsv(const testing::OpticalAxisScenario& s, bool depths = true) {
  std::ostringstream csv;
  csv.precision(17);
  csv << "robot,camera_robot,axis,index,set,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,du_px,"
         "dv_px,depth_mm,offset_x_mm,offset_y_mm,offset_z_mm,frames,moves\n";
  int index = 0, last_axis = -1;
  for (const AxisSample& smp : s.samples) {
    index = smp.axis == last_axis ? index + 1 : 0;
    last_axis = smp.axis;
    const Line3& axis = s.axes[smp.axis];
    const double depth = (EndPose(s.truth, smp.q).translation() - axis.point).dot(axis.direction);
    csv << "r2,r1," << smp.axis << ',' << index << ',' << (smp.axis < 3 ? "calibration" : "validation");
    for (int i = 0; i < 6; ++i) csv << ',' << RadToDeg(smp.q(i));
    csv << ",0,0,";
    if (depths) csv << 1000 * depth;
    // else: an empty field, no depth measured
    csv << ",0,0,0,3,2\n";
  }
  return csv.str();
}

// With depths, the synthetic model's tool link (theta -90 deg, a 60 mm) given as the board
// mount: the scale is measured and the identification is exact. (With the whole mount in X_LtE
// and an identity link 7, this point on the flange plane's y axis had no first-order parameter
// along y and the solve stopped at 0.05 mm; BoardRobotModel now puts the mount's translation
// into link 7's parameters.)
TEST(CalibrationCli, IdentifyWithDepthsAndABoardMountIsExact) {
  const fs::path dir = TempDir("identify_depth");
  const auto s = testing::MakeOpticalAxisScenario(42);
  std::ofstream(dir / "nominal.yaml") << ModelToYaml(s.nominal);
  std::ofstream(dir / "measurements.csv") << SyntheticCsv(s, true);
  const CliRun r = Twinbench("identify --model " + (dir / "nominal.yaml").string() +
                             " --measurements " + (dir / "measurements.csv").string() +
                             " --board-mount 0,-60,0,0,0,-90 --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "out" / "identification.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& m = j["misaligned_error_mm"];
  std::printf("[ measured ] identify with depths: calibration %.3g -> %.3g mm, validation %.3g "
              "-> %.3g mm\n",
              m["calibration"]["before"].get<double>(), m["calibration"]["after"].get<double>(),
              m["validation"]["before"].get<double>(), m["validation"]["after"].get<double>());
  EXPECT_EQ(j["method"], "ceres_with_scale_all_axes");
  EXPECT_GT(m["calibration"]["before"].get<double>(), 0.1);
  // Exact data: the synthetic servo floor (1e-7 m); 1e-3 mm leaves margin.
  EXPECT_LT(m["calibration"]["after"].get<double>(), 1e-3);
  EXPECT_LT(m["validation"]["after"].get<double>(), 1e-3);
}

// Without depths (a recording of the paper's method: collinearity only); the scale
// measurement is tested in tests/calib/identification/scale_measurement_test.cc.
TEST(CalibrationCli, IdentifyRecoversASyntheticRecording) {
  const fs::path dir = TempDir("identify");
  const auto s = testing::MakeOpticalAxisScenario(42);
  std::ofstream(dir / "nominal.yaml") << ModelToYaml(s.nominal);
  std::ofstream(dir / "measurements.csv") << SyntheticCsv(s, false);
  // Collinearity only, board mount 0: link 7 of the identified model absorbs the synthetic
  // model's tool offset (lateral data alone cannot tell them apart).
  const CliRun r = Twinbench("identify --model " + (dir / "nominal.yaml").string() +
                             " --measurements " + (dir / "measurements.csv").string() +
                             " --out " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir / "out" / "identification.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& m = j["misaligned_error_mm"];
  std::printf("[ measured ] identify on the synthetic recording: calibration %.3g -> %.3g mm, "
              "validation %.3g -> %.3g mm\n",
              m["calibration"]["before"].get<double>(), m["calibration"]["after"].get<double>(),
              m["validation"]["before"].get<double>(), m["validation"]["after"].get<double>());
  // No depth column: Ceres without the scale; the delivered model is the refit on all axes
  // after the hold-out validation (OpticalAxisOptions::refit_all_axes, on by default).
  EXPECT_EQ(j["method"], "ceres_all_axes");
  EXPECT_GT(m["calibration"]["before"].get<double>(), 0.1);  // mm-level nominal error
  // Exact data: the identified model is the truth up to the synthetic servo floor (1e-7 m,
  // optical_axis_synthetic.h); 1e-3 mm leaves margin, on axes it never saw too.
  EXPECT_LT(m["calibration"]["after"].get<double>(), 1e-3);
  EXPECT_LT(m["validation"]["after"].get<double>(), 1e-3);
  EXPECT_TRUE(fs::exists(dir / "out" / "identified_r2.yaml"));
}

TEST(CalibrationCli, IdentifyNamesABadRow) {
  const fs::path dir = TempDir("badrow");
  const auto s = testing::MakeOpticalAxisScenario(42);
  std::ofstream(dir / "nominal.yaml") << ModelToYaml(s.nominal);
  std::string csv = SyntheticCsv(s);
  const auto third_line = csv.find('\n', csv.find('\n', csv.find('\n') + 1) + 1) + 1;
  csv.insert(third_line, "r2,r1,0,9,calibration,1,2,x,4,5,6,0,0,300,0,0,0,3,2\n");
  std::ofstream(dir / "measurements.csv") << csv;
  const CliRun r = Twinbench("identify --model " + (dir / "nominal.yaml").string() +
                             " --measurements " + (dir / "measurements.csv").string() +
                             " --out " + (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("measurements.csv:4 q3_deg"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "identification.json"));
}

}  // namespace
}  // namespace twin
