#include "bench/io/model_loader.h"

#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {

const std::string kModels = std::string(TWIN_SOURCE_DIR) + "/models/";

std::string ErrorOf(const std::string& path) {
  try {
    LoadRobotModel(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The committed URDFs (written by `twinbench export-urdf`) must describe the same arms as the
// YAML files: the same end pose at random joint angles inside the limits.
TEST(ModelFiles, CommittedUrdfEqualsYamlModel) {
  for (const char* robot : {"reinovo_r1", "reinovo_r2"}) {
    const KinematicModel yaml = LoadRobotModel(kModels + robot + ".yaml");
    const KinematicModel urdf = LoadRobotModel(kModels + robot + ".urdf");
    std::mt19937_64 rng(5);
    for (int k = 0; k < 200; ++k) {
      JointVector q(6);
      for (int i = 0; i < 6; ++i) {
        q(i) = std::uniform_real_distribution<double>(yaml.links[i].limits.lower,
                                                      yaml.links[i].limits.upper)(rng);
      }
      const Transform a = EndPose(yaml, q), b = EndPose(urdf, q);
      // 1e-9 m and 1e-9 rad: the bound; the URDF is written with 17 digits, so the
      // difference is rounding of the two chains only.
      EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9) << robot;
      EXPECT_LT(Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle(), 1e-9) << robot;
    }
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR(yaml.links[i].limits.lower, urdf.links[i].limits.lower, 1e-12);
      EXPECT_NEAR(yaml.links[i].limits.upper, urdf.links[i].limits.upper, 1e-12);
    }
  }
}

TEST(LoadRobotModel, UnknownExtensionNamesThePath) {
  const std::string msg = ErrorOf("robot.json");
  EXPECT_NE(msg.find("robot.json"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected a .yaml, .yml or .urdf file"), std::string::npos) << msg;
}

TEST(LoadRobotModel, MissingFilesNameThePath) {
  for (const std::string path : {"/nonexistent/r.yaml", "/nonexistent/r.urdf"}) {
    const std::string msg = ErrorOf(path);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
  }
}

TEST(WriteFileAtomically, WritesTheTextAndLeavesNoPartialFile) {
  const std::string path = ::testing::TempDir() + "/atomic_test.txt";
  WriteFileAtomically(path, "hello\n");
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "hello");
  EXPECT_FALSE(std::ifstream(path + ".partial").good());
  std::remove(path.c_str());
}

TEST(WriteFileAtomically, UnwritableDirectoryIsAnInputErrorAndWritesNothing) {
  const std::string path = "/nonexistent_dir/out.urdf";
  try {
    WriteFileAtomically(path, "x");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::ifstream(path).good());
}

}  // namespace
}  // namespace twin
