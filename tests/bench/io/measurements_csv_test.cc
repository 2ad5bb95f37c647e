#include "bench/io/measurements_csv.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

std::string Write(const std::string& name, const std::string& text) {
  const fs::path p = fs::path(::testing::TempDir()) / ("measurements_csv_" + name + ".csv");
  std::ofstream(p) << text;
  return p.string();
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

MeasurementRow Row(const std::string& robot, int axis, int index, const std::string& set,
                   double scale) {
  MeasurementRow r;
  r.robot = robot;
  r.camera_robot = "r1";
  r.axis = axis;
  r.index = index;
  r.set = set;
  r.q = JointVector(6);
  for (int i = 0; i < 6; ++i) r.q(i) = scale * (0.3 * i - 0.7) + 1e-7 * index;
  r.du_px = 0.0123456 * scale;
  r.dv_px = -0.0654321;
  r.depth_m = 0.4123456789 + 0.01 * index;
  r.offset = Vector3(1e-5, -2e-5, 3.3e-5) * scale;
  r.frames = 3 + index;
  r.moves = 2;
  r.du0_px = 12.5;
  r.dv0_px = -7.25;
  r.pose_rms_px = 0.0432;
  r.time_s = 60.0 * index;
  r.temperature_delta_K = index == 1 ? MeasurementRow::kNone : 0.25;  // no sensor reading
  return r;
}

// The reader gives back what the writer wrote, to the digits the writer keeps: 10 significant
// digits for angles (in degrees), depths and offsets (in mm) and times, 6 for pixels and
// temperatures, 4 for the pose RMS; NaN stays NaN (an empty field).
TEST(MeasurementsCsv, WhatIsWrittenReadsBack) {
  const std::vector<MeasurementRow> rows = {Row("r2", 0, 0, "calibration", 1.0),
                                            Row("r1", 0, 0, "calibration", 0.5),  // another robot
                                            Row("r2", 0, 1, "calibration", 1.1),
                                            Row("r2", 3, 0, "validation", 0.9),
                                            Row("r2", 4, 0, "unused", 1.2)};
  std::string text = MeasurementsCsvHeader(7) + "\n";  // one joint column more than the robot
  for (const MeasurementRow& r : rows) text += MeasurementsCsvRow(r, 7) + "\n";
  const std::string path = Write("roundtrip", text);
  const MeasurementsFile f = ReadMeasurementsCsv(path, 6);
  EXPECT_EQ(f.robot, "r2");  // the first row's
  EXPECT_TRUE(f.has_depth);
  EXPECT_TRUE(f.has_offset);
  ASSERT_EQ(f.rows.size(), 4u);
  EXPECT_EQ(f.lines, (std::vector<int>{2, 4, 5, 6}));
  const auto rel = [](double a, double b, double digits) {
    return std::abs(a - b) <= std::pow(10.0, -digits) * std::max(std::abs(a), 1e-300) * 5;
  };
  int k = 0;
  for (const MeasurementRow& want : {rows[0], rows[2], rows[3], rows[4]}) {
    const MeasurementRow& got = f.rows[k++];
    EXPECT_EQ(got.robot, want.robot);
    EXPECT_EQ(got.camera_robot, want.camera_robot);
    EXPECT_EQ(got.axis, want.axis);
    EXPECT_EQ(got.index, want.index);
    EXPECT_EQ(got.set, want.set);
    ASSERT_EQ(got.q.size(), 6);
    for (int i = 0; i < 6; ++i) {
      EXPECT_TRUE(rel(RadToDeg(got.q(i)), RadToDeg(want.q(i)), 10)) << i << ": " << got.q(i);
    }
    EXPECT_TRUE(rel(got.du_px, want.du_px, 6));
    EXPECT_TRUE(rel(got.dv_px, want.dv_px, 6));
    EXPECT_TRUE(rel(got.depth_m, want.depth_m, 10));
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(rel(got.offset(i), want.offset(i), 10)) << i;
    EXPECT_EQ(got.frames, want.frames);
    EXPECT_EQ(got.moves, want.moves);
    EXPECT_TRUE(rel(got.du0_px, want.du0_px, 6));
    EXPECT_TRUE(rel(got.dv0_px, want.dv0_px, 6));
    EXPECT_TRUE(rel(got.pose_rms_px, want.pose_rms_px, 4));
    if (want.index == 0) {
      EXPECT_EQ(got.time_s, 0.0);
    } else {
      EXPECT_TRUE(rel(got.time_s, want.time_s, 10));
    }
    EXPECT_EQ(std::isnan(got.temperature_delta_K), std::isnan(want.temperature_delta_K));
    if (!std::isnan(want.temperature_delta_K)) {
      EXPECT_TRUE(rel(got.temperature_delta_K, want.temperature_delta_K, 6));
    }
  }
  // The other robot's rows by name; writing what was read gives the same text again.
  const MeasurementsFile r1 = ReadMeasurementsCsv(path, 6, "r1");
  ASSERT_EQ(r1.rows.size(), 1u);
  std::string again = MeasurementsCsvHeader(6) + "\n";
  std::string direct = again;
  for (const MeasurementRow& r : f.rows) again += MeasurementsCsvRow(r, 6) + "\n";
  for (const MeasurementRow& r : {rows[0], rows[2], rows[3], rows[4]}) {
    direct += MeasurementsCsvRow(r, 6) + "\n";
  }
  EXPECT_EQ(again, direct);
}

// Only the required columns: the optional figures read as not recorded.
TEST(MeasurementsCsv, OptionalColumnsMayBeMissingOrEmpty) {
  const std::string path = Write("minimal", "robot,axis,index,set,q1_deg,q2_deg\n"
                                            "a,0,0,calibration,10,20\n"
                                            "a,1,0,validation,-10,5.5\n");
  const MeasurementsFile f = ReadMeasurementsCsv(path, 2);
  ASSERT_EQ(f.rows.size(), 2u);
  EXPECT_FALSE(f.has_depth);
  EXPECT_FALSE(f.has_offset);
  EXPECT_NEAR(RadToDeg(f.rows[1].q(1)), 5.5, 1e-12);
  EXPECT_TRUE(std::isnan(f.rows[0].depth_m));
  EXPECT_TRUE(std::isnan(f.rows[0].time_s));
  EXPECT_EQ(f.rows[0].frames, -1);
  EXPECT_EQ(f.rows[0].camera_robot, "");
}

TEST(MeasurementsCsv, BadRowsAreRefusedNamingFileLineAndColumn) {
  const std::string head = "robot,axis,index,set,q1_deg,depth_mm,time_s\n";
  std::string e = ErrorOf([&] {
    ReadMeasurementsCsv(Write("bothsets", head + "a,0,0,calibration,1,400,\na,0,1,validation,2,410,\n"), 1);
  });
  EXPECT_NE(e.find("axis 0 has rows in both the calibration and the validation set"),
            std::string::npos) << e;
  e = ErrorOf([&] { ReadMeasurementsCsv(Write("set", head + "a,0,0,training,1,400,\n"), 1); });
  EXPECT_NE(e.find(":2 set: expected calibration, validation or unused, got 'training'"),
            std::string::npos) << e;
  e = ErrorOf([&] { ReadMeasurementsCsv(Write("depth", head + "a,0,0,calibration,1,0,\n"), 1); });
  EXPECT_NE(e.find(":2 depth_mm: expected a camera depth in (0, 10000] mm"), std::string::npos)
      << e;
  e = ErrorOf([&] { ReadMeasurementsCsv(Write("time", head + "a,0,0,calibration,1,400,soon\n"), 1); });
  EXPECT_NE(e.find(":2 time_s"), std::string::npos) << e;
  e = ErrorOf([&] { ReadMeasurementsCsv(Write("noq", "robot,axis,index,set\n"), 1); });
  EXPECT_NE(e.find(":1: missing column 'q1_deg'"), std::string::npos) << e;
  e = ErrorOf([&] { ReadMeasurementsCsv(Write("norows", head + "a,0,0,calibration,1,400,\n"), 1, "b"); });
  EXPECT_NE(e.find("no rows for robot 'b'"), std::string::npos) << e;
  e = ErrorOf([&] { ReadMeasurementsCsv(Write("name", head + "../x,0,0,calibration,1,400,\n"), 1); });
  EXPECT_NE(e.find(":2 robot: expected a robot name"), std::string::npos) << e;
}

}  // namespace
}  // namespace twin
