#include "bench/io/tracker_file.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

const std::string kModel = std::string(TWIN_SOURCE_DIR) + "/models/motoman_sda10_right.yaml";
const std::string kHeader = "pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,q_T_rad,x_m,y_m,z_m,sigma_m\n";
const std::string kRow = "1,0.0,-0.16,0.59,-0.43,-1.29,0.14,-0.94,-2.84,0.85,-0.39,7e-06\n";

std::string Write(const std::string& name, const std::string& text) {
  const fs::path p = fs::path(::testing::TempDir()) / ("tracker_file_" + name + ".csv");
  std::ofstream(p) << text;
  return p.string();
}

// The message of the InputError ReadTrackerFile throws ("" when it reads the file).
std::string Refusal(const std::string& text, const std::vector<std::string>& ignore = {"q_E_rad"},
                    const std::string& name = "bad") {
  const std::string path = Write(name, text);
  try {
    ReadTrackerFile(path, LoadRobotModel(kModel), ignore);
  } catch (const InputError& e) {
    return std::string(e.what());
  }
  return "";
}

TEST(TrackerFile, ReadsJointsPositionsAndSigmasWithTheirUnits) {
  const std::string path = Write("good", kHeader + kRow + "2,0.0001,0.1,0.2,0.3,0.4,0.5,0.6,1,2,3,5e-06\n");
  ASSERT_TRUE(IsTrackerFile(path));
  const TrackerFile f = ReadTrackerFile(path, LoadRobotModel(kModel), {"q_E_rad"});
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_DOUBLE_EQ(f.points[0].context.q(0), -0.16);
  EXPECT_DOUBLE_EQ(f.points[1].context.q(5), 0.6);
  EXPECT_DOUBLE_EQ(f.points[1].p_T.z(), 3.0);
  EXPECT_DOUBLE_EQ(f.points[0].sigma, 7e-6);
  EXPECT_EQ(f.points[1].row, 3);
  ASSERT_EQ(f.ignored.size(), 1u);
  EXPECT_DOUBLE_EQ(f.ignored[0].max, 0.0001);
  // Degrees and millimetres by the column names, joints by number.
  const std::string mm = Write("mm", "q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,x_mm,y_mm,z_mm\n"
                                     "90,0,0,0,0,0,1000,0,0\n");
  const TrackerFile g = ReadTrackerFile(mm, LoadRobotModel(kModel));
  EXPECT_NEAR(g.points[0].context.q(0), 1.5707963267948966, 1e-15);
  EXPECT_DOUBLE_EQ(g.points[0].p_T.x(), 1.0);
  EXPECT_FALSE(g.has_sigma);
}

TEST(TrackerFile, BadFilesAreRefusedNamingFileLineAndColumn) {
  // A model joint the file lacks.
  std::string e = Refusal("pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,x_m,y_m,z_m\n");
  EXPECT_NE(e.find(":1"), std::string::npos) << e;
  EXPECT_NE(e.find("joint 6 of 6"), std::string::npos) << e;
  // A joint column the model lacks (7 joint columns for a 6-joint model), not ignored.
  e = Refusal(kHeader + kRow, {});
  EXPECT_NE(e.find("column 2"), std::string::npos) << e;
  EXPECT_NE(e.find("q_E_rad"), std::string::npos) << e;
  EXPECT_NE(e.find("--ignore-column"), std::string::npos) << e;
  // An unknown column.
  e = Refusal("pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,q_T_rad,x_m,y_m,z_m,colour\n");
  EXPECT_NE(e.find("unknown column 'colour'"), std::string::npos) << e;
  // A missing position column.
  e = Refusal("pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,q_T_rad,x_m,y_m\n");
  EXPECT_NE(e.find("missing the column 'z_m'"), std::string::npos) << e;
  // A duplicated header column.
  e = Refusal("pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,q_T_rad,x_m,y_m,z_m,x_m\n");
  EXPECT_NE(e.find("'x_m' appears twice"), std::string::npos) << e;
  // A non-numeric cell, with its line and column.
  e = Refusal(kHeader + kRow + "2,0,0.1,abc,0.3,0.4,0.5,0.6,1,2,3,5e-06\n");
  EXPECT_NE(e.find(":3 column 4 (q_L_rad)"), std::string::npos) << e;
  EXPECT_NE(e.find("'abc'"), std::string::npos) << e;
  // NaN and infinity.
  e = Refusal(kHeader + "2,0,0.1,0.2,0.3,0.4,0.5,0.6,nan,2,3,5e-06\n");
  EXPECT_NE(e.find(":2 column 9 (x_m)"), std::string::npos) << e;
  e = Refusal(kHeader + "2,0,0.1,0.2,0.3,0.4,0.5,0.6,1,inf,3,5e-06\n");
  EXPECT_NE(e.find("column 10 (y_m)"), std::string::npos) << e;
  // A header repeated inside the file reads as non-numeric cells.
  e = Refusal(kHeader + kRow + kHeader);
  EXPECT_NE(e.find(":3 column"), std::string::npos) << e;
  EXPECT_NE(e.find("got 'q_"), std::string::npos) << e;
  // A row with a missing field.
  e = Refusal(kHeader + "2,0,0.1,0.2,0.3,0.4,0.5,0.6,1,2,3\n");
  EXPECT_NE(e.find("expected 12 fields"), std::string::npos) << e;
  // Absurd values: a reflector 1 km away (a unit mix-up), a sigma of 1 m, joints in degrees
  // under a _rad column.
  e = Refusal(kHeader + "2,0,0.1,0.2,0.3,0.4,0.5,0.6,1000,2,3,5e-06\n");
  EXPECT_NE(e.find("beyond 100 m"), std::string::npos) << e;
  e = Refusal(kHeader + "2,0,0.1,0.2,0.3,0.4,0.5,0.6,1,2,3,1\n");
  EXPECT_NE(e.find("sigma"), std::string::npos) << e;
  e = Refusal(kHeader + "2,0,90,0.2,0.3,0.4,0.5,0.6,1,2,3,5e-06\n");
  EXPECT_NE(e.find("two turns"), std::string::npos) << e;
  // No rows; an --ignore-column the file lacks.
  e = Refusal(kHeader);
  EXPECT_NE(e.find("no data rows"), std::string::npos) << e;
  e = Refusal(kHeader + kRow, {"q_X_rad"});
  EXPECT_NE(e.find("--ignore-column"), std::string::npos) << e;
}

}  // namespace
}  // namespace twin
