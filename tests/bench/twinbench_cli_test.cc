// Runs the built twinbench binary: user errors must exit with code 2 and a message naming the
// bad input; good input exits 0.
#include "tests/bench/cli_run.h"
#include <sys/wait.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>

#include <gtest/gtest.h>

namespace {

using twin::testing::CliRun;
using twin::testing::Twinbench;

const std::string kModel = std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r1.yaml";

TEST(TwinbenchCli, HelpListsTheSubcommands) {
  const CliRun r = Twinbench("--help");
  EXPECT_EQ(r.code, 0);
  for (const char* verb : {"info", "fk", "ik", "export-urdf", "demo"}) {
    EXPECT_NE(r.output.find(verb), std::string::npos) << verb;
  }
}

// The version line carries CMake's project version (passed to this test by CMake, not read from
// the binary) and `git describe` of the tree: an abbreviated commit, maybe tagged and -dirty,
// or "unknown" when built outside a git checkout.
TEST(TwinbenchCli, VersionPrintsTheProjectVersionAndTheCommit) {
  const CliRun r = Twinbench("--version");
  EXPECT_EQ(r.code, 0);
  const std::string expected_start = std::string("twinbench ") + TWINBENCH_PROJECT_VERSION + " (";
  EXPECT_EQ(r.output.rfind(expected_start, 0), 0u) << r.output;
  const std::size_t open = r.output.find('('), close = r.output.find(')');
  ASSERT_NE(close, std::string::npos) << r.output;
  const std::string describe = r.output.substr(open + 1, close - open - 1);
  EXPECT_TRUE(describe == "unknown" ||
              describe.find_first_not_of("0123456789abcdefghijklmnopqrstuvwxyz.-_") ==
                  std::string::npos)
      << describe;
  EXPECT_GE(describe.size(), 7u) << describe;  // git's shortest abbreviation is 7 hex digits
}

TEST(TwinbenchCli, UnknownSubcommandExitsTwo) {
  EXPECT_EQ(Twinbench("frobnicate").code, 2);
}

TEST(TwinbenchCli, MissingModelFileExitsTwoNamingIt) {
  const CliRun r = Twinbench("info /nonexistent/model.yaml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("/nonexistent/model.yaml"), std::string::npos) << r.output;
}

TEST(TwinbenchCli, WrongJointCountExitsTwo) {
  const CliRun r = Twinbench("fk " + kModel + " --q 0,0,0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("expected 6 comma-separated numbers"), std::string::npos) << r.output;
}

TEST(TwinbenchCli, NonNumericJointExitsTwo) {
  const CliRun r = Twinbench("fk " + kModel + " --q 0,0,abc,0,0,0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("expected a number, got 'abc'"), std::string::npos) << r.output;
}

TEST(TwinbenchCli, UnreachableIkTargetExitsTwoWithTheReason) {
  const CliRun r = Twinbench("ik " + kModel + " --xyz 3000,0,0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("target not solvable"), std::string::npos) << r.output;
}

// Reads "xyz [x, y, z] mm, rpy [r, p, y] deg" from fk's output.
bool ParsePose(const std::string& out, double v[6]) {
  const size_t at = out.find("xyz [");
  return at != std::string::npos &&
         std::sscanf(out.c_str() + at, "xyz [%lf, %lf, %lf] mm, rpy [%lf, %lf, %lf]", &v[0], &v[1],
                     &v[2], &v[3], &v[4], &v[5]) == 6;
}

TEST(TwinbenchCli, IkOfAnFkPoseReproducesIt) {
  const CliRun fk = Twinbench("fk " + kModel + " --q 10,20,30,40,50,60");
  ASSERT_EQ(fk.code, 0) << fk.output;
  double pose[6];
  ASSERT_TRUE(ParsePose(fk.output, pose)) << fk.output;
  char args[256];
  std::snprintf(args, sizeof(args), " --xyz %.4f,%.4f,%.4f --rpy %.4f,%.4f,%.4f", pose[0], pose[1],
                pose[2], pose[3], pose[4], pose[5]);
  const CliRun ik = Twinbench("ik " + kModel + args);
  ASSERT_EQ(ik.code, 0) << ik.output;
  const size_t at = ik.output.find("q [deg]:");
  ASSERT_NE(at, std::string::npos) << ik.output;
  double q[6];
  ASSERT_EQ(std::sscanf(ik.output.c_str() + at, "q [deg]: %lf %lf %lf %lf %lf %lf", &q[0], &q[1],
                        &q[2], &q[3], &q[4], &q[5]), 6);
  std::snprintf(args, sizeof(args), " --q %.6f,%.6f,%.6f,%.6f,%.6f,%.6f", q[0], q[1], q[2], q[3],
                q[4], q[5]);
  const CliRun back = Twinbench("fk " + kModel + args);
  double pose2[6];
  ASSERT_TRUE(ParsePose(back.output, pose2)) << back.output;
  // 2e-3 mm: the poses are printed with 4 decimals (mm, deg) and the joints with 6 (deg).
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(pose[i], pose2[i], 2e-3) << i;
}

TEST(TwinbenchCli, UrdfChainOptionsWarningsAndJointNames) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "cli_urdf_links";
  fs::remove_all(dir);
  fs::create_directories(dir);
  // reinovo_r1.urdf renamed as a vendor would (joint 2 "shoulder_lift") with a frame-only
  // `base` leaf beside base_link (ROS-Industrial).
  std::ifstream in(std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r1.urdf");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (auto [from, to] : {std::pair<std::string, std::string>{"\"joint2\"", "\"shoulder_lift\""},
                          {"<link name=\"base_link\"/>",
                           "<link name=\"base_link\"/><link name=\"base\"/><joint "
                           "name=\"b\" type=\"fixed\"><parent link=\"base_link\"/><child "
                           "link=\"base\"/></joint>"}}) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const std::string urdf = (dir / "arm.urdf").string();
  std::ofstream(urdf) << text;

  const CliRun automatic = Twinbench("fk " + urdf + " --q 10,20,30,40,50,60");
  EXPECT_EQ(automatic.code, 0) << automatic.output;
  EXPECT_NE(automatic.output.find("warning: " + urdf + ": tip_link not given: chose 'end'"),
            std::string::npos) << automatic.output;
  const CliRun from_yaml = Twinbench("fk " + kModel + " --q 10,20,30,40,50,60");
  double a[6], b[6];
  ASSERT_TRUE(ParsePose(automatic.output, a)) << automatic.output;
  ASSERT_TRUE(ParsePose(from_yaml.output, b)) << from_yaml.output;
  // The same arm: poses printed to 1e-4 mm / deg agree to their last digit.
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(a[i], b[i], 2e-4) << i;

  const CliRun chosen = Twinbench("fk " + urdf + " --base-link base_link --tip-link end --q 0,0,0,0,0,0");
  EXPECT_EQ(chosen.code, 0) << chosen.output;
  EXPECT_EQ(chosen.output.find("warning:"), std::string::npos) << chosen.output;

  const CliRun limits = Twinbench("fk " + urdf + " --tip-link end --q 0,200,0,0,0,0");
  EXPECT_EQ(limits.code, 2) << limits.output;
  EXPECT_NE(limits.output.find("joint 2 ('shoulder_lift') at 200 deg is outside its limits"),
            std::string::npos) << limits.output;

  const CliRun bad_tip = Twinbench("info " + urdf + " --tip-link nope");
  EXPECT_EQ(bad_tip.code, 2) << bad_tip.output;
  EXPECT_NE(bad_tip.output.find("tip_link 'nope' is not a link"), std::string::npos)
      << bad_tip.output;
  const CliRun yaml_tip = Twinbench("info " + kModel + " --tip-link tool");
  EXPECT_EQ(yaml_tip.code, 2) << yaml_tip.output;
  EXPECT_NE(yaml_tip.output.find("a YAML model is already one chain"), std::string::npos)
      << yaml_tip.output;
  fs::remove_all(dir);
}

TEST(TwinbenchCli, RenderWritesHandCameraAndOverviewPngs) {
  namespace fs = std::filesystem;
  const fs::path out = fs::path(::testing::TempDir()) / "render_cli_test";
  fs::remove_all(out);
  const CliRun r = Twinbench("render " + std::string(TWIN_SOURCE_DIR) +
                             "/scenarios/twin_demo.yaml --poses 2 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"hand_camera_00.png", "overview_00.png", "hand_camera_01.png"}) {
    EXPECT_GT(fs::file_size(out / f), 1000u) << f;  // a real image, not an empty file
  }
  EXPECT_FALSE(fs::exists(out.string() + ".partial"));
  fs::remove_all(out);
}

TEST(TwinbenchCli, RenderOfABadScenarioExitsTwoAndWritesNothing) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "render_bad_scenario";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ifstream in(std::string(TWIN_SOURCE_DIR) + "/scenarios/twin_demo.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find("square_mm: 20");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 13, "square_mm: -20");
  const size_t models = text.find("../models/");
  ASSERT_NE(models, std::string::npos);
  // model paths are relative to the scenario's folder: point them back at the repository
  for (size_t p = 0; (p = text.find("../models/", p)) != std::string::npos; p += 10) {
    text.replace(p, 10, std::string(TWIN_SOURCE_DIR) + "/models/");
  }
  std::ofstream(dir / "bad.yaml") << text;
  const CliRun r = Twinbench("render " + (dir / "bad.yaml").string() + " --out " +
                             (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("board.square"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace
