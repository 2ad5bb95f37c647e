#include "bench/io/tracker_file.h"

#include <unistd.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

const std::string kModel = std::string(TWIN_SOURCE_DIR) + "/models/motoman_sda10_right.yaml";
const std::string kHeader = "pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,q_T_rad,x_m,y_m,z_m,sigma_m\n";
const std::string kRow = "1,0.0,-0.16,0.59,-0.43,-1.29,0.14,-0.94,-2.84,0.85,-0.39,7e-06\n";

// A file of this test's own (ctest runs the tests of this file side by side: a shared name made
// one read what the other wrote).
std::string Write(const std::string& name, const std::string& text) {
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const fs::path p = fs::path(::testing::TempDir()) /
                     ("tracker_file_" + test + "_" + std::to_string(::getpid()) + "_" + name +
                      ".csv");
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

// A file of `n` poses spread over the joint ranges, the reflector at the nominal model's end
// frame (the tracker at the base), written with positions in metres under `xyz_unit`'s labels
// and a torso column (q_E_rad) whose value at row k is torso(k).
std::string PlausibleFile(int n, const std::string& xyz_unit, double scale_to_file,
                          const std::function<double(int)>& torso,
                          const std::function<double(int)>& sigma) {
  const KinematicModel model = LoadRobotModel(kModel);
  std::ostringstream os;
  os.precision(12);
  os << "pose,q_E_rad,q_S_rad,q_L_rad,q_U_rad,q_R_rad,q_B_rad,q_T_rad,x_" << xyz_unit << ",y_"
     << xyz_unit << ",z_" << xyz_unit << ",sigma_m\n";
  for (int k = 0; k < n; ++k) {
    JointVector q(6);
    for (int j = 0; j < 6; ++j) q(j) = 0.6 * std::sin(1.3 * k + 0.7 * j);
    const Vector3 p = EndPose(model, q).translation() * scale_to_file;
    os << k + 1 << "," << torso(k);
    for (int j = 0; j < 6; ++j) os << "," << q(j);
    os << "," << p.x() << "," << p.y() << "," << p.z() << "," << sigma(k) << "\n";
  }
  return os.str();
}

TEST(TrackerFile, FilesThatContradictThemselvesAreRefusedWithTheReason) {
  const auto still = [](int) { return 3.1e-5; };
  const auto even = [](int) { return 1e-5; };
  // The plausible file reads (the checks do not fire on a consistent file).
  EXPECT_EQ(Refusal(PlausibleFile(30, "m", 1.0, still, even)), "");
  // Metres under _mm labels: the positions spread 1000 times less than the motion.
  std::string e = Refusal(PlausibleFile(30, "mm", 1.0, still, even));
  EXPECT_NE(e.find(":1 column 9 (x_mm)"), std::string::npos) << e;
  EXPECT_NE(e.find("the values look like metres"), std::string::npos) << e;
  // Millimetres under _m labels (within 100 m of the tracker, so only the spread tells).
  e = Refusal(PlausibleFile(30, "m", 30.0, still, even));
  EXPECT_NE(e.find("look like millimetres"), std::string::npos) << e;
  // One row's sigma of 1e-300 m would outweigh every other row: refused, naming the row.
  e = Refusal(PlausibleFile(30, "m", 1.0, still, [](int k) { return k == 7 ? 1e-300 : 1e-5; }));
  EXPECT_NE(e.find(":9 column 12 (sigma_m)"), std::string::npos) << e;
  EXPECT_NE(e.find("more than 100 times below the file's median"), std::string::npos) << e;
  // A 62-fold spread of sigmas, as in the real Leica session, is accepted.
  EXPECT_EQ(Refusal(PlausibleFile(30, "m", 1.0, still,
                                  [](int k) { return k == 3 ? 6.2e-5 : k == 4 ? 1e-6 : 7e-6; })),
            "");
  // An ignored torso column that moves by 1 rad is no constant axis.
  e = Refusal(PlausibleFile(30, "m", 1.0, [](int k) { return k == 5 ? 1.0 : 0.0; }, even));
  EXPECT_NE(e.find("--ignore-column q_E_rad"), std::string::npos) << e;
  EXPECT_NE(e.find("must be constant"), std::string::npos) << e;
  // The real session's torso jitter (2.7e-4 rad) is constant.
  EXPECT_EQ(Refusal(PlausibleFile(30, "m", 1.0, [](int k) { return k % 2 ? 1.66e-4 : -1.04e-4; },
                                  even)),
            "");
}

TEST(TrackerFile, RepeatedPosesAreCountedAsRepeats) {
  // 8 poses measured 4 times each (the rows copied), then 2 new ones.
  const std::string one = PlausibleFile(10, "m", 1.0, [](int) { return 0.0; },
                                        [](int) { return 1e-5; });
  std::istringstream in(one);
  std::string header, line;
  std::getline(in, header);
  std::vector<std::string> rows;
  while (std::getline(in, line)) rows.push_back(line);
  std::string text = header + "\n";
  for (int copy = 0; copy < 4; ++copy) {
    for (int k = 0; k < 8; ++k) text += rows[k] + "\n";
  }
  text += rows[8] + "\n" + rows[9] + "\n";
  const std::string path = Write("repeats", text);
  const TrackerFile f = ReadTrackerFile(path, LoadRobotModel(kModel), {"q_E_rad"});
  ASSERT_EQ(f.points.size(), 34u);
  EXPECT_EQ(f.distinct_poses, 10);
  ASSERT_EQ(f.pose_group.size(), 34u);
  EXPECT_EQ(f.pose_group[0], f.pose_group[8]);
  EXPECT_EQ(f.pose_group[7], f.pose_group[31]);
  EXPECT_NE(f.pose_group[0], f.pose_group[1]);
  EXPECT_EQ(f.pose_group[33], 9);
}

}  // namespace
}  // namespace twin
