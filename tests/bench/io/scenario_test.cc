#include "bench/io/scenario.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"
#include "text_edit.h"
#include "calib/kinematics/forward_kinematics.h"
#include "sim/effects/effect.h"

namespace twin {
namespace {

using testing::LineOf;
using testing::ReadFile;
using testing::Replaced;

const std::string kRoot = TWIN_SOURCE_DIR;
const std::string kDemoPath = kRoot + "/scenarios/twin_demo.yaml";
const std::string kScenarioDir = kRoot + "/scenarios";
const std::string kSource = "scenarios/test.yaml";
const std::string kHandEye = "hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 0, 0]}";

// Unit conversions (mm / 1000, deg * pi / 180) and rotation products cost a few ulp of values
// of order 1..1000, far below 1e-12.
constexpr double kExact = 1e-12;

std::string DemoText() { return ReadFile(kDemoPath); }

/// "scenarios/test.yaml:<line>", the location prefix the parser must report.
std::string At(int line) { return kSource + ":" + std::to_string(line); }

Scenario Parse(const std::string& text) { return ParseScenario(text, kSource, kScenarioDir); }

/// The what() of the InputError that parsing text throws (a test failure if none).
std::string ParseError(const std::string& text) {
  try {
    Parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return "";
}

::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' lacks '" << part << "'";
}

Matrix3 Rot(const Vector3& axis, double deg) {
  return Eigen::AngleAxisd(DegToRad(deg), axis).toRotationMatrix();
}
Matrix3 Rx(double deg) { return Rot(Vector3::UnitX(), deg); }
Matrix3 Ry(double deg) { return Rot(Vector3::UnitY(), deg); }
Matrix3 Rz(double deg) { return Rot(Vector3::UnitZ(), deg); }

double MaxDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

JointVector Deg(double a, double b, double c, double d, double e, double f) {
  JointVector q(6);
  q << DegToRad(a), DegToRad(b), DegToRad(c), DegToRad(d), DegToRad(e), DegToRad(f);
  return q;
}

// ---- The shipped demo ----

TEST(ScenarioTest, LoadsTwinDemoInSiUnits) {
  const Scenario s = LoadScenario(kDemoPath);
  EXPECT_EQ(s.name, "twin_demo");
  EXPECT_EQ(s.path, kDemoPath);
  EXPECT_EQ(s.twin.seed, 7u);
  EXPECT_EQ(s.robot_names[0], "r1");
  EXPECT_EQ(s.robot_names[1], "r2");
  // Model paths are resolved against the scenario's folder and normalised.
  EXPECT_EQ(s.model_paths[0], kRoot + "/models/reinovo_r1.yaml");
  EXPECT_EQ(s.model_paths[1], kRoot + "/models/reinovo_r2.yaml");

  const RobotSpec& r1 = s.twin.robots[0];
  const RobotSpec& r2 = s.twin.robots[1];
  EXPECT_EQ(r1.model.name, "r1");
  EXPECT_EQ(r2.model.name, "r2");
  EXPECT_NEAR(r1.model.links[5].dh.d, 0.1215, kExact);  // the two tables differ only in d6
  EXPECT_NEAR(r2.model.links[5].dh.d, 0.131, kExact);
  EXPECT_EQ(r1.installation, Installation::kFloor);
  EXPECT_EQ(r2.installation, Installation::kFloor);
  EXPECT_LE(MaxDiff(r1.X_WB.matrix(), Eigen::Matrix4d::Identity()), kExact);
  EXPECT_LE(MaxDiff(r2.X_WB.translation(), Vector3(1.2, 0.0, 0.0)), kExact);
  EXPECT_LE(MaxDiff(r2.X_WB.linear(), Rz(180)), kExact);
  EXPECT_LE(MaxDiff(r1.q_initial, Deg(0, 34, -34, 0, 90, 90)), kExact);
  EXPECT_LE(MaxDiff(r2.q_initial, Deg(0, 39, -36, 0, 87, 90)), kExact);

  const CameraSpec& cam = s.twin.camera;
  EXPECT_EQ(cam.robot, 0);
  EXPECT_EQ(cam.intrinsics.width, 1024);
  EXPECT_EQ(cam.intrinsics.height, 768);
  EXPECT_NEAR(cam.intrinsics.fx, 834.31, kExact);
  EXPECT_NEAR(cam.intrinsics.fy, 833.38, kExact);
  EXPECT_NEAR(cam.intrinsics.cx, 513.56, kExact);
  EXPECT_NEAR(cam.intrinsics.cy, 403.95, kExact);
  EXPECT_FALSE(cam.distortion.Any());
  EXPECT_EQ(cam.msaa_samples, 4);
  EXPECT_TRUE(cam.skybox);  // absent: the sky
  EXPECT_LE(MaxDiff(cam.X_FC.translation(), Vector3(0, 0, 0.05)), kExact);
  EXPECT_LE(MaxDiff(cam.X_FC.linear(), Matrix3::Identity()), kExact);
  EXPECT_EQ(cam.near_m, CameraSpec{}.near_m);  // absent: the struct's defaults, exactly
  EXPECT_EQ(cam.far_m, CameraSpec{}.far_m);

  const BoardSpec& b = s.twin.board;
  EXPECT_EQ(b.robot, 1);
  EXPECT_EQ(b.squares_x, 4);
  EXPECT_EQ(b.squares_y, 4);
  EXPECT_NEAR(b.square_m, 0.020, kExact);
  EXPECT_NEAR(b.margin_m, 0.010, kExact);
  EXPECT_NEAR(b.thickness_m, 0.004, kExact);
  EXPECT_NEAR(b.mass_kg, 0.2, kExact);
  EXPECT_LE(MaxDiff(b.X_FT.translation(), Vector3(0, 0, 0.04)), kExact);

  ASSERT_EQ(s.twin.effects.size(), 1u);
  const EffectSpec& e = s.twin.effects[0];
  EXPECT_EQ(e.type, "geometry_errors");
  EXPECT_TRUE(e.declared);
  EXPECT_EQ(e.robot, -1);
  EXPECT_EQ(e.joint, -1);
  ASSERT_EQ(e.params.size(), 2u);
  EXPECT_EQ(e.params.at("sigma_length_mm"), 0.5);  // parameters keep their file units
  EXPECT_EQ(e.params.at("sigma_angle_deg"), 0.05);
  EXPECT_EQ(e.where, kDemoPath + ":" + std::to_string(LineOf(DemoText(), "- type:")) +
                         " scenario.effects[0]");

  // Absent sections: the structs' defaults.
  EXPECT_EQ(s.twin.physics.timestep_s, PhysicsSpec{}.timestep_s);
  EXPECT_EQ(s.twin.physics.max_steps, PhysicsSpec{}.max_steps);
  EXPECT_TRUE(s.twin.physics.gravity);
  EXPECT_EQ(s.twin.tips[1].length_m, TipSpec{}.length_m);
}

TEST(ScenarioTest, TwinDemoCameraSeesTheBoard) {
  // The file's comment claims the board origin P is 0.3-0.6 m in front of the camera and
  // inside the image at the initial pose (nominal geometry); recompute it.
  const Scenario s = LoadScenario(kDemoPath);
  const TwinSpec& t = s.twin;
  const RobotSpec& rc = t.robots[t.camera.robot];
  const RobotSpec& rb = t.robots[t.board.robot];
  const Transform X_WC =
      rc.X_WB * ForwardKinematics(rc.model, rc.q_initial).flange() * t.camera.X_FC;
  const Transform X_WT =
      rb.X_WB * ForwardKinematics(rb.model, rb.q_initial).flange() * t.board.X_FT;
  const Vector3 p_CP = (X_WC.inverse() * X_WT).translation();
  EXPECT_GT(p_CP.z(), 0.3);
  EXPECT_LT(p_CP.z(), 0.6);
  const Intrinsics& in = t.camera.intrinsics;
  const double u = in.fx * p_CP.x() / p_CP.z() + in.cx;
  const double v = in.fy * p_CP.y() / p_CP.z() + in.cy;
  EXPECT_GT(u, 0.0);
  EXPECT_LT(u, in.width - 1.0);
  EXPECT_GT(v, 0.0);
  EXPECT_LT(v, in.height - 1.0);
  // The board faces the camera: its normal z_T points back along the optical axis z_C.
  const double cos_angle = -(X_WC.linear().col(2)).dot(X_WT.linear().col(2));
  EXPECT_GT(cos_angle, std::cos(DegToRad(30.0)));
}

// ---- Rotation conventions ----

TEST(ScenarioTest, RpyIsFixedAxesAsUrdf) {
  const std::string text = Replaced(DemoText(), kHandEye,
                                    "hand_eye: {xyz_mm: [10, -20, 30], rpy_deg: [10, 20, 30]}");
  const Transform& X = Parse(text).twin.camera.X_FC;
  EXPECT_LE(MaxDiff(X.linear(), Rz(30) * Ry(20) * Rx(10)), kExact);
  EXPECT_GT(MaxDiff(X.linear(), Rx(10) * Ry(20) * Rz(30)), 0.1);  // not the other order
  EXPECT_LE(MaxDiff(X.translation(), Vector3(0.010, -0.020, 0.030)), kExact);
}

TEST(ScenarioTest, ZyzIsGanEulerAndRobot2IsRelativeToRobot1) {
  // Robot 1 off the origin and turned; robot 2 given relative to it with ZYZ angles
  // (a floor-floor row of Gan et al. 2014, Table 1: (37.9, 1476.5, 54.5) mm, (-0.001, 0.001,
  // -44.5) deg).
  std::string text = Replaced(DemoText(), "base: {xyz_mm: [0, 0, 0], rpy_deg: [0, 0, 0]}",
                              "base: {xyz_mm: [100, 200, 0], rpy_deg: [0, 0, 90]}");
  text = Replaced(text, "base_from_robot1: {xyz_mm: [1200, 0, 0], zyz_deg: [180, 0, 0]}",
                  "base_from_robot1: {xyz_mm: [37.9, 1476.5, 54.5], "
                  "zyz_deg: [-0.001, 0.001, -44.5]}");
  const Scenario s = Parse(text);
  Transform X_WB1 = Transform::Identity();
  X_WB1.translation() = Vector3(0.1, 0.2, 0.0);
  X_WB1.linear() = Rz(90);
  Transform X_B1B2 = Transform::Identity();
  X_B1B2.translation() = Vector3(0.0379, 1.4765, 0.0545);
  X_B1B2.linear() = Rz(-0.001) * Ry(0.001) * Rz(-44.5);
  EXPECT_LE(MaxDiff(s.twin.robots[0].X_WB.matrix(), X_WB1.matrix()), kExact);
  EXPECT_LE(MaxDiff(s.twin.robots[1].X_WB.matrix(), (X_WB1 * X_B1B2).matrix()), kExact);
}

TEST(ScenarioTest, ZyzDiffersFromRpyForTheSameNumbers) {
  const std::string mount = "mount: {xyz_mm: [0, 0, 40], rpy_deg: [0, 0, 0]}";
  const std::string zyz =
      Replaced(DemoText(), mount, "mount: {xyz_mm: [0, 0, 40], zyz_deg: [30, 40, 50]}");
  const std::string rpy =
      Replaced(DemoText(), mount, "mount: {xyz_mm: [0, 0, 40], rpy_deg: [30, 40, 50]}");
  const Matrix3 R_zyz = Parse(zyz).twin.board.X_FT.linear();
  const Matrix3 R_rpy = Parse(rpy).twin.board.X_FT.linear();
  EXPECT_LE(MaxDiff(R_zyz, Rz(30) * Ry(40) * Rz(50)), kExact);
  EXPECT_LE(MaxDiff(R_rpy, Rz(50) * Ry(40) * Rx(30)), kExact);
  EXPECT_GT(MaxDiff(R_zyz, R_rpy), 0.1);
}

TEST(ScenarioErrorTest, PoseNeedsExactlyOneRotation) {
  const std::string both = Replaced(DemoText(), kHandEye,
                                    "hand_eye: {xyz_mm: [0, 0, 50], rpy_deg: [0, 0, 0], "
                                    "zyz_deg: [0, 0, 0]}");
  const std::string msg = ParseError(both);
  EXPECT_TRUE(Contains(msg, At(LineOf(both, "hand_eye: {")) + " scenario.camera.hand_eye.zyz_deg"));
  EXPECT_TRUE(Contains(msg, "expected exactly one of rpy_deg and zyz_deg, got both"));
  const std::string none = Replaced(DemoText(), kHandEye,
                                    "hand_eye: {xyz_mm: [0, 0, 50]}");
  EXPECT_TRUE(Contains(ParseError(none), "scenario.camera.hand_eye: missing rotation"));
}

// ---- Options and conversions ----

TEST(ScenarioTest, OptionalSectionsAreConvertedToSi) {
  std::string text = Replaced(DemoText(), "    msaa: 4\n",
                              "    msaa: 0\n"
                              "    skybox: false\n"
                              "    distortion: [-0.1, 0.02, 0.001, -0.002, 0.003]\n"
                              "    near_mm: 50\n"
                              "    far_mm: 3000\n");
  text = Replaced(text, "  effects:\n",
                  "  tips:\n"
                  "    r2: {xyz_mm: [0, 0, 80], zyz_deg: [0, 0, 90], length_mm: 70, "
                  "radius_mm: 3}\n"
                  "  physics:\n"
                  "    timestep_s: 0.001\n"
                  "    stiffness_Nm_per_rad: 2.0e5\n"
                  "    armature_kgm2: 0.2\n"
                  "    max_joint_speed_deg_s: 90\n"
                  "    settle_speed_deg_s: 0.001\n"
                  "    settle_steps: 30\n"
                  "    max_steps: 5000\n"
                  "    gravity: false\n"
                  "  effects:\n"
                  "    - type: transmission_error\n"
                  "      declared: false\n"
                  "      robot: r2\n"
                  "      joint: 3\n"
                  "      amplitude_deg: 0.02\n"
                  "      harmonic: 2\n");
  const Scenario s = Parse(text);
  const CameraSpec& cam = s.twin.camera;
  EXPECT_EQ(cam.msaa_samples, 0);
  EXPECT_FALSE(cam.skybox);
  EXPECT_EQ(cam.distortion.k1, -0.1);
  EXPECT_EQ(cam.distortion.k2, 0.02);
  EXPECT_EQ(cam.distortion.p1, 0.001);
  EXPECT_EQ(cam.distortion.p2, -0.002);
  EXPECT_EQ(cam.distortion.k3, 0.003);
  EXPECT_NEAR(cam.near_m, 0.05, kExact);
  EXPECT_NEAR(cam.far_m, 3.0, kExact);

  const TipSpec& tip = s.twin.tips[1];
  EXPECT_LE(MaxDiff(tip.X_FTip.translation(), Vector3(0, 0, 0.08)), kExact);
  EXPECT_LE(MaxDiff(tip.X_FTip.linear(), Rz(90)), kExact);
  EXPECT_NEAR(tip.length_m, 0.07, kExact);
  EXPECT_NEAR(tip.radius_m, 0.003, kExact);
  EXPECT_TRUE(s.twin.tips[0].X_FTip.matrix().isIdentity(0.0));  // r1 has no entry

  const PhysicsSpec& p = s.twin.physics;
  EXPECT_NEAR(p.timestep_s, 0.001, kExact);
  EXPECT_NEAR(p.stiffness, 2e5, kExact);
  EXPECT_NEAR(p.armature, 0.2, kExact);
  EXPECT_NEAR(p.max_joint_speed, kPi / 2, kExact);
  EXPECT_NEAR(p.settle_speed, DegToRad(0.001), kExact);
  EXPECT_EQ(p.settle_steps, 30);
  EXPECT_EQ(p.max_steps, 5000);
  EXPECT_FALSE(p.gravity);

  ASSERT_EQ(s.twin.effects.size(), 2u);
  const EffectSpec& e = s.twin.effects[0];
  EXPECT_EQ(e.type, "transmission_error");
  EXPECT_FALSE(e.declared);
  EXPECT_EQ(e.robot, 1);
  EXPECT_EQ(e.joint, 2);  // joint 3 in the file, 0-based in EffectSpec
  EXPECT_EQ(e.params.size(), 2u);
  EXPECT_EQ(e.params.at("amplitude_deg"), 0.02);
  EXPECT_EQ(e.params.at("harmonic"), 2.0);
  EXPECT_EQ(e.where, At(LineOf(text, "- type: transmission_error")) + " scenario.effects[0]");
}

TEST(ScenarioTest, ModelPathIsRelativeToTheScenarioFolder) {
  // A scenario and a model copied into a fresh folder tree, loaded from elsewhere.
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "scenario_test_paths";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "cells");
  std::filesystem::create_directories(dir / "arms");
  std::filesystem::copy_file(kRoot + "/models/reinovo_r1.yaml", dir / "arms" / "left.yaml");
  std::string text = Replaced(DemoText(), "model: ../models/reinovo_r1.yaml",
                              "model: ../arms/left.yaml");
  text = Replaced(text, "model: ../models/reinovo_r2.yaml", "model: " + kRoot +
                                                               "/models/reinovo_r2.yaml");
  const std::string path = (dir / "cells" / "cell.yaml").string();
  std::ofstream(path) << text;
  const Scenario s = LoadScenario(path);
  EXPECT_EQ(s.model_paths[0], (dir / "arms" / "left.yaml").string());
  EXPECT_EQ(s.model_paths[1], kRoot + "/models/reinovo_r2.yaml");  // absolute: as written
  EXPECT_EQ(s.twin.robots[0].model.name, "r1");
  std::filesystem::remove_all(dir);
}

TEST(ScenarioTest, UrdfRobotsTakeBaseAndTipLinksAndTheirWarnings) {
  // reinovo_r1.urdf with a frame-only `base` leaf beside base_link, as ROS-Industrial URDFs
  // have: loads without tip_link (with a warning naming the robot); tip_link picks the chain.
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / "scenario_test_links";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "r1.urdf") << Replaced(
      ReadFile(kRoot + "/models/reinovo_r1.urdf"), "<link name=\"base_link\"/>",
      "<link name=\"base_link\"/>\n  <link name=\"base\"/>\n  <joint name=\"base_link-base\" "
      "type=\"fixed\"><parent link=\"base_link\"/><child link=\"base\"/></joint>");
  const std::string text = Replaced(DemoText(), "model: ../models/reinovo_r1.yaml",
                                    "model: " + (dir / "r1.urdf").string());
  const Scenario automatic = ParseScenario(text, kSource, kScenarioDir);
  bool named = false;
  for (const std::string& w : automatic.warnings) {
    named |= Contains(w, "robot r1: ") && Contains(w, "chose 'end'");
  }
  EXPECT_TRUE(named) << ::testing::PrintToString(automatic.warnings);
  const KinematicModel yaml = LoadRobotModel(kRoot + "/models/reinovo_r1.yaml");
  const JointVector q = Deg(10, 40, -30, 20, 70, -15);
  // The committed URDF equals the YAML model to 1e-9 m (ModelFiles test); so does this one.
  EXPECT_LT((EndPose(automatic.twin.robots[0].model, q).translation() -
             EndPose(yaml, q).translation()).norm(), 1e-9);

  // tip_link: tool ends the chain before the fixed tool-to-end transform.
  const std::string with_tip =
      Replaced(text, "model: " + (dir / "r1.urdf").string(),
               "model: " + (dir / "r1.urdf").string() + "\n      base_link: base_link\n"
               "      tip_link: tool");
  const Scenario chosen = ParseScenario(with_tip, kSource, kScenarioDir);
  EXPECT_TRUE(chosen.warnings.empty()) << ::testing::PrintToString(chosen.warnings);
  const KinematicModel& m = chosen.twin.robots[0].model;
  EXPECT_LT((EndPose(m, q).translation() -
             (EndPose(yaml, q) * yaml.X_LtE.inverse()).translation()).norm(), 1e-9);

  // A wrong link name is refused at the model's line, naming the link.
  const std::string bad = Replaced(with_tip, "tip_link: tool", "tip_link: tool9");
  EXPECT_TRUE(Contains(ParseError(bad), "tip_link 'tool9' is not a link"));
  EXPECT_TRUE(Contains(ParseError(bad), "scenario.robots[0].model"));
  // base_link / tip_link of a YAML model.
  const std::string yaml_tip = Replaced(DemoText(), "model: ../models/reinovo_r1.yaml",
                                        "model: ../models/reinovo_r1.yaml\n      tip_link: tool");
  EXPECT_TRUE(Contains(ParseError(yaml_tip), "a YAML model is already one chain"));
  std::filesystem::remove_all(dir);
}

// ---- Bad input: each message names file:line key.path and what was expected ----

TEST(ScenarioErrorTest, MissingFileNamesPath) {
  const std::string path = "/nonexistent/dir/cell.yaml";
  try {
    LoadScenario(path);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), path);
    EXPECT_TRUE(Contains(e.what(), "cannot open file"));
  }
}

TEST(ScenarioErrorTest, MissingModelNamesScenarioLineAndResolvedPath) {
  // The same text read as if it sat in the repository root: ../models leaves the repository.
  const std::string text = DemoText();
  try {
    ParseScenario(text, kSource, kRoot);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string resolved =
        (std::filesystem::path(kRoot) / "../models/reinovo_r1.yaml").lexically_normal().string();
    EXPECT_EQ(e.where(), At(LineOf(text, "model: ../models/reinovo_r1")) +
                             " scenario.robots[0].model");
    EXPECT_TRUE(Contains(e.message(), "cannot load robot model '../models/reinovo_r1.yaml' "
                                      "(resolved to " + resolved + ")"));
    EXPECT_TRUE(Contains(e.message(), "cannot open file"));
  }
}

TEST(ScenarioErrorTest, MalformedYaml) {
  const std::string msg = ParseError(Replaced(DemoText(), "squares: [4, 4]", "squares: [4, 4"));
  EXPECT_TRUE(Contains(msg, kSource + ":"));
  EXPECT_TRUE(Contains(msg, "malformed YAML"));
}

TEST(ScenarioErrorTest, UnknownKeyNamesLineAndAllowedKeys) {
  const std::string text = Replaced(DemoText(), "    fy: 833.38\n", "    fy: 833.38\n    f: 1\n");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "    f: 1")) + " scenario.camera.f: unknown key 'f' "
                            "(allowed: robot, hand_eye, resolution, fx, fy, cx, cy, distortion, "
                            "msaa, skybox, near_mm, far_mm)"));
}

TEST(ScenarioErrorTest, UnknownKeyInPoseAndAtTheTop) {
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "mount: {xyz_mm:", "mount: {xyz_m:")),
                       "scenario.board.mount.xyz_m: unknown key 'xyz_m' (allowed: xyz_mm, "
                       "rpy_deg, zyz_deg)"));
  EXPECT_TRUE(Contains(ParseError(DemoText() + "extra: 1\n"),
                       "unknown key 'extra' (allowed: scenario)"));
}

TEST(ScenarioErrorTest, Robot2TakesItsBaseRelativeToRobot1) {
  const std::string text = Replaced(DemoText(), "base_from_robot1:", "base:");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, "scenario.robots[1].base: unknown key 'base' (allowed: name, model, "
                            "base_link, tip_link, installation, base_from_robot1, "
                            "initial_joints_deg, temperature_sensor)"));
}

TEST(ScenarioErrorTest, MissingKeyIsNamed) {
  const std::string text = Replaced(DemoText(), "    square_mm: 20\n", "");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "robot: r2")) + " scenario.board: missing "
                            "required key 'square_mm'"));
}

TEST(ScenarioErrorTest, OneOrTwoRobots) {
  // Three: the first two again, the second renamed.
  std::string text = DemoText();
  const std::size_t begin = text.find("    - name: r1");
  const std::size_t end = text.find("  camera:");
  const std::string third = Replaced(text.substr(text.find("    - name: r2"),
                                                 end - text.find("    - name: r2")),
                                     "name: r2", "name: r3");
  text.insert(end, third);
  std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "    - name: r1")) + " scenario.robots: expected a "
                            "sequence of one robot (a laser-tracker cell) or two (with the "
                            "camera and the board), got a sequence of 3 items"));
  // None.
  text = DemoText();
  text.replace(begin, end - begin, "");
  text = Replaced(text, "  robots:\n", "  robots: []\n");
  msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, "scenario.robots: expected a sequence of one robot"));
  EXPECT_TRUE(Contains(msg, "got a sequence of 0 items"));
}

// ---- A one-robot cell: the arm alone with a laser tracker ----

const std::string kSinglePath = kRoot + "/scenarios/tracker_single_reinovo.yaml";

std::string SingleText() { return ReadFile(kSinglePath); }

TEST(ScenarioOneRobotTest, TheShippedTrackerCellLoadsWithOneRobotAndNoCameraOrBoard) {
  const Scenario s = LoadScenario(kSinglePath);
  EXPECT_EQ(s.name, "tracker_single_reinovo");
  EXPECT_EQ(s.twin.num_robots, 1);
  EXPECT_FALSE(s.twin.HasCameraAndBoard());
  EXPECT_FALSE(s.twin.intrinsics_target.has_value());
  ASSERT_EQ(s.robot_names, std::vector<std::string>{"r1"});
  ASSERT_EQ(s.model_paths.size(), 1u);
  EXPECT_EQ(s.model_paths[0], kRoot + "/models/reinovo_r2.yaml");
  EXPECT_EQ(s.twin.robots[0].model.name, "r1");
  EXPECT_EQ(s.twin.robots[0].model.num_joints(), 6);
  EXPECT_TRUE(s.twin.tracker.present);
  EXPECT_EQ(s.twin.tracker.robot, 0);
  EXPECT_TRUE(IsPresent(s.tracker_calibration));
  EXPECT_FALSE(IsPresent(s.calibration));
  EXPECT_FALSE(IsPresent(s.handclasp));
  ASSERT_EQ(s.twin.effects.size(), 2u);
  EXPECT_EQ(s.twin.effects[0].robot, -1);  // every robot: the one
  // Tips of its one robot are read as usual.
  const Scenario tipped = Parse(Replaced(SingleText(), "  effects:\n",
                                         "  tips: {r1: {length_mm: 50}}\n  effects:\n"));
  EXPECT_NEAR(tipped.twin.tips[0].length_m, 0.05, kExact);
}

// A two-robot cell's camera section, to paste into the one-robot file.
std::string CameraSection() {
  const std::string demo = DemoText();
  const std::size_t a = demo.find("  camera:\n"), b = demo.find("  board:\n");
  return demo.substr(a, b - a);
}

TEST(ScenarioOneRobotTest, ACameraBoardOrIntrinsicsTargetIsRefusedAtItsKey) {
  for (const std::string& section :
       {CameraSection(), std::string("  board: {robot: r1, squares: [4, 4], square_mm: 20, "
                                     "mount: {xyz_mm: [0, 0, 40], rpy_deg: [0, 0, 0]}}\n"),
        std::string("  intrinsics_target: {squares: [14, 10], square_mm: 20}\n")}) {
    const std::string text = Replaced(SingleText(), "  effects:\n", section + "  effects:\n");
    const std::string key = section.substr(2, section.find(':') - 2);
    // A block map is located at its first key, the line after its own key.
    const bool block = section.compare(2 + key.size(), 2, ":\n") == 0;
    const int line = LineOf(text, "  " + key + ":") + (block ? 1 : 0);
    EXPECT_TRUE(Contains(ParseError(text),
                         At(line) + " scenario." + key + ": is not allowed with one robot: a "
                         "one-robot cell is a laser-tracker cell, without camera, board or "
                         "intrinsics target"));
  }
}

TEST(ScenarioOneRobotTest, CalibrationOrHandclaspIsRefusedAsNeedingTwoRobots) {
  for (const std::string key : {"calibration", "handclasp"}) {
    const std::string text = Replaced(SingleText(), "  acceptance:\n",
                                      "  " + key + ": {robots: [r1]}\n  acceptance:\n");
    const std::string msg = ParseError(text);
    EXPECT_TRUE(Contains(msg, At(LineOf(text, "  " + key + ":")) + " scenario." + key +
                              ": is not allowed with one robot"));
    EXPECT_TRUE(Contains(msg, "need two robots"));
  }
}

TEST(ScenarioOneRobotTest, WithoutTrackerCalibrationItIsRefusedAtRobots) {
  std::string text = SingleText();
  const std::size_t a = text.find("  tracker_calibration:\n"), b = text.find("  acceptance:\n");
  text.erase(a, b - a);
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "    - name: r1")) + " scenario.robots: lists one "
                            "robot, and a one-robot cell runs only the laser-tracker "
                            "procedure"));
}

TEST(ScenarioOneRobotTest, ASecondRobotsNameIsUnknown) {
  EXPECT_TRUE(Contains(ParseError(Replaced(SingleText(), "  effects:\n",
                                           "  tips: {r2: {}}\n  effects:\n")),
                       "scenario.tips.r2: unknown key 'r2' (allowed: r1)"));
  const std::string text = Replaced(SingleText(), "    - type: encoder_noise\n",
                                    "    - type: encoder_noise\n      robot: r2\n");
  EXPECT_TRUE(Contains(ParseError(text), At(LineOf(text, "robot: r2")) +
                                             " scenario.effects[1].robot: unknown robot 'r2' "
                                             "(robots: r1)"));
  EXPECT_TRUE(Contains(ParseError(Replaced(SingleText(), "  tracker:\n    robot: r1\n",
                                           "  tracker:\n    robot: r2\n")),
                       "scenario.tracker.robot: unknown robot 'r2' (robots: r1)"));
}

TEST(ScenarioOneRobotTest, ImageNoiseHasNoCameraToActOn) {
  const std::string text = Replaced(SingleText(), "    - type: encoder_noise\n",
                                    "    - type: image_noise\n      sigma_levels: 1\n"
                                    "    - type: encoder_noise\n");
  EXPECT_TRUE(Contains(ParseError(text), At(LineOf(text, "    - type: image_noise") ) +
                                             " scenario.effects[1]"));
  EXPECT_TRUE(Contains(ParseError(text), "a one-robot cell does not have"));
}

TEST(ScenarioErrorTest, DuplicateRobotName) {
  const std::string text = Replaced(DemoText(), "- name: r2", "- name: r1");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "- name: r1\n      model: ../models/reinovo_r2")) +
                            " scenario.robots[1].name"));
  EXPECT_TRUE(Contains(msg, "robot name 'r1' is already used by robots[0]"));
}

TEST(ScenarioErrorTest, WrongListLength) {
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "[1024, 768]", "[1024]")),
                       "scenario.camera.resolution: expected a sequence of 2 whole numbers, "
                       "got a sequence of 1 items"));
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "[0, 34, -34, 0, 90, 90]", "[0, 34, -34]")),
                       "scenario.robots[0].initial_joints_deg: expected a sequence of 6 numbers"));
}

TEST(ScenarioErrorTest, NonNumericValue) {
  const std::string text = Replaced(DemoText(), "fx: 834.31", "fx: abc");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "fx: abc")) + " scenario.camera.fx: expected a "
                            "number, got 'abc'"));
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "squares: [4, 4]", "squares: [4, 4.5]")),
                       "scenario.board.squares[1]: expected a whole number, got '4.5'"));
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "sigma_angle_deg: 0.05",
                                           "sigma_angle_deg: [0.05]")),
                       "scenario.effects[0].sigma_angle_deg: expected a number, got a "
                       "sequence of 1 items"));
}

TEST(ScenarioErrorTest, UnknownInstallation) {
  const std::string msg = ParseError(Replaced(DemoText(), "installation: floor",
                                              "installation: roof"));
  EXPECT_TRUE(Contains(msg, "scenario.robots[0].installation: expected floor, wall or ceiling, "
                            "got 'roof'"));
}

TEST(ScenarioErrorTest, UnknownRobotNames) {
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "robot: r1", "robot: r3")),
                       "scenario.camera.robot: unknown robot 'r3' (robots: r1, r2)"));
  EXPECT_TRUE(Contains(ParseError(Replaced(DemoText(), "  effects:\n", "  tips: {r9: {}}\n"
                                                                       "  effects:\n")),
                       "scenario.tips.r9: unknown key 'r9' (allowed: r1, r2)"));
}

TEST(ScenarioErrorTest, UnknownRobotInEffect) {
  const std::string text = Replaced(DemoText(), "    - type: geometry_errors\n",
                                    "    - type: geometry_errors\n      robot: left\n");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "robot: left")) + " scenario.effects[0].robot: "
                            "unknown robot 'left' (robots: r1, r2)"));
}

TEST(ScenarioErrorTest, JointSevenOfASixAxisArmIsRefused) {
  const std::string text = Replaced(DemoText(), "    - type: geometry_errors\n",
                                    "    - type: geometry_errors\n      joint: 7\n");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "joint: 7")) + " scenario.effects[0].joint: "
                            "expected a joint number from 1 to 6, got 7"));
  EXPECT_TRUE(Contains(ParseError(Replaced(text, "joint: 7", "joint: 0")),
                       "expected a joint number from 1 to 6, got 0"));
}

TEST(ScenarioErrorTest, UnknownEffectTypeIsNamed) {
  // MakeEffect refuses it, naming the effect's place in the file and listing the known types.
  const std::string text = Replaced(DemoText(), "type: geometry_errors", "type: warp_drive");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "- type: warp_drive")) + " scenario.effects[0]"));
  EXPECT_TRUE(Contains(msg, "warp_drive"));
  for (const std::string& type : EffectTypes()) EXPECT_TRUE(Contains(msg, type));
}

// ---- Values that parse but ValidateTwinSpec refuses: reported at their line ----

TEST(ScenarioErrorTest, NegativeSquareSizeAtItsLine) {
  const std::string text = Replaced(DemoText(), "square_mm: 20", "square_mm: -20");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "square_mm: -20")) + " scenario.board.square_mm: "
                            "board.square_m must be a finite number > 0 m, got -0.02"));
}

TEST(ScenarioErrorTest, ZeroFocalLengthAtItsLine) {
  const std::string text = Replaced(DemoText(), "fy: 833.38", "fy: 0");
  EXPECT_TRUE(Contains(ParseError(text), At(LineOf(text, "fy: 0")) + " scenario.camera.fy: "
                                         "camera.intrinsics.fy must be a finite number > 0 px"));
}

TEST(ScenarioErrorTest, CameraAndBoardOnTheSameRobot) {
  const std::string text = Replaced(DemoText(), "robot: r2", "robot: r1");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "    robot: r1\n    squares")) +
                            " scenario.board.robot: board.robot must differ from camera.robot"));
}

TEST(ScenarioErrorTest, InitialJointOutOfLimitsAtItsItem) {
  const std::string text =
      Replaced(DemoText(), "[0, 39, -36, 0, 87, 90]", "[0, 39, -150, 0, 87, 90]");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "-150")) + " scenario.robots[1].initial_joints_deg[2]: "
                            "robots[1].q_initial[2] must be within joint 3's limits "
                            "[-140, 140] deg, got -150 deg"));
}

// A robot's temperature sensor (robots[i].temperature_sensor): absent unless given, its
// values as written; an absurd noise or ambient is refused at its line.
TEST(ScenarioTest, ATemperatureSensorIsReadFromItsRobotEntry) {
  EXPECT_FALSE(Parse(DemoText()).twin.robots[1].temperature_sensor.present);
  const std::string text =
      Replaced(DemoText(), "[0, 39, -36, 0, 87, 90]",
               "[0, 39, -36, 0, 87, 90]\n      temperature_sensor: {ambient_C: 22.5, sigma_K: 0.2}");
  const TemperatureSensorSpec s = Parse(text).twin.robots[1].temperature_sensor;
  EXPECT_TRUE(s.present);
  EXPECT_EQ(s.ambient_C, 22.5);
  EXPECT_EQ(s.sigma_K, 0.2);
  EXPECT_FALSE(Parse(text).twin.robots[0].temperature_sensor.present);
  const std::string noisy = Replaced(text, "sigma_K: 0.2", "sigma_K: 50");
  EXPECT_TRUE(Contains(ParseError(noisy),
                       At(LineOf(noisy, "sigma_K: 50")) +
                           " scenario.robots[1].temperature_sensor.sigma_K: "
                           "robots[1].temperature_sensor.sigma_K must be 0 to 10 K, got 50"));
  const std::string hot = Replaced(text, "ambient_C: 22.5", "ambient_C: 295");
  EXPECT_TRUE(Contains(ParseError(hot), "robots[1].temperature_sensor.ambient_C must be -40 to "
                                        "80 deg C, got 295"));
  EXPECT_TRUE(Contains(ParseError(Replaced(text, "sigma_K", "sigma_k")), "sigma_k"));
}

TEST(ScenarioErrorTest, WallInstallationWithUprightBase) {
  const std::string text = Replaced(DemoText(), "reinovo_r2.yaml\n      installation: floor",
                                    "reinovo_r2.yaml\n      installation: wall");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "installation: wall")) +
                            " scenario.robots[1].installation: robots[1].installation is wall"));
  EXPECT_TRUE(Contains(msg, "expected within 5 deg of horizontal"));
  // Turned 90 deg about y (ZYZ (0, 90, 0)), the same robot is a wall robot.
  const std::string wall = Replaced(text, "zyz_deg: [180, 0, 0]", "zyz_deg: [0, 90, 0]");
  EXPECT_EQ(Parse(wall).twin.robots[1].installation, Installation::kWall);
}

TEST(ScenarioErrorTest, DefaultedFieldFallsBackToItsSection) {
  // near_mm beyond the default far plane: the far plane was not written, so the message points
  // at the camera section.
  const std::string text =
      Replaced(DemoText(), "    msaa: 4\n", "    msaa: 4\n    near_mm: 6000\n");
  const std::string msg = ParseError(text);
  EXPECT_TRUE(Contains(msg, At(LineOf(text, "robot: r1")) + " scenario.camera: camera.far_m must "
                            "be beyond camera.near_m = 6 m, got 5"));
}

}  // namespace
}  // namespace twin

// ---- Seeds: one for the truth, one for the estimator ----

namespace twin {
namespace {

TEST(ScenarioSeedsTest, SeedDrivesBothStreams) {
  const Scenario s = Parse(DemoText());  // twin_demo.yaml: seed: 7
  EXPECT_EQ(s.seeds.truth, 7u);
  EXPECT_EQ(s.seeds.estimator, 7u);
  EXPECT_EQ(s.twin.seed, 7u);
  EXPECT_EQ(s.trial, 0);
}

TEST(ScenarioSeedsTest, SeedsSetTruthAndEstimatorApart) {
  const Scenario s = Parse(Replaced(DemoText(), "seed: 7", "seeds: {truth: 11, estimator: 42}"));
  EXPECT_EQ(s.seeds.truth, 11u);
  EXPECT_EQ(s.seeds.estimator, 42u);
  EXPECT_EQ(s.twin.seed, 11u);  // the twin draws from the truth seed only
  const Scenario d = Parse(Replaced(DemoText(), "seed: 7", "seeds: {estimator: 42}"));
  EXPECT_EQ(d.seeds.truth, 1u);  // the default of an absent key
  EXPECT_EQ(d.seeds.estimator, 42u);
}

TEST(ScenarioSeedsTest, TrialOffsetsBothSeeds) {
  Scenario s = Parse(Replaced(DemoText(), "seed: 7", "seeds: {truth: 11, estimator: 42}"));
  ApplyTrial(5, &s);
  EXPECT_EQ(s.trial, 5);
  EXPECT_EQ(s.seeds.truth, 16u);
  EXPECT_EQ(s.seeds.estimator, 47u);
  EXPECT_EQ(s.twin.seed, 16u);
  ApplyTrial(2, &s);  // relative to the file's seeds, not to the last trial
  EXPECT_EQ(s.seeds.truth, 13u);
  EXPECT_EQ(s.seeds.estimator, 44u);
  try {
    ApplyTrial(-1, &s);
    ADD_FAILURE() << "a negative trial was accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(Contains(e.what(), "--trial"));
  }
}

TEST(ScenarioSeedsTest, ANoiseSeedIsOptionalAndFollowsTheTrial) {
  Scenario s = Parse(Replaced(DemoText(), "seed: 7", "seeds: {truth: 11, estimator: 42}"));
  EXPECT_FALSE(s.seeds.noise.has_value());
  EXPECT_FALSE(s.twin.noise_seed.has_value());  // the twin's noise comes from the truth seed
  s = Parse(Replaced(DemoText(), "seed: 7", "seeds: {truth: 11, estimator: 42, noise: 90}"));
  ASSERT_TRUE(s.seeds.noise.has_value());
  EXPECT_EQ(*s.seeds.noise, 90u);
  EXPECT_EQ(s.twin.seed, 11u);  // the geometry still from the truth seed
  ASSERT_TRUE(s.twin.noise_seed.has_value());
  EXPECT_EQ(*s.twin.noise_seed, 90u);
  ApplyTrial(3, &s);
  EXPECT_EQ(*s.seeds.noise, 93u);
  EXPECT_EQ(*s.twin.noise_seed, 93u);
  EXPECT_EQ(s.twin.seed, 14u);
  try {
    Parse(Replaced(DemoText(), "seed: 7", "seeds: {truth: 11, noise: -2}"));
    ADD_FAILURE() << "a negative noise seed was accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(Contains(e.what(), "seeds.noise")) << e.what();
  }
}

TEST(ScenarioSeedsTest, SeedAndSeedsTogetherAreRefusedAtTheirLine) {
  const std::string text =
      Replaced(DemoText(), "seed: 7", "seed: 7\n  seeds: {truth: 1, estimator: 2}");
  const std::string e = ParseError(text);
  EXPECT_TRUE(Contains(e, At(LineOf(text, "seeds:")) + " scenario.seeds"));
  EXPECT_TRUE(Contains(e, "not both"));
  const std::string bad = Replaced(DemoText(), "seed: 7", "seeds: {truth: 1, nosie: 2}");
  EXPECT_TRUE(Contains(ParseError(bad), "unknown key 'nosie' (allowed: truth, estimator, noise"))
      << ParseError(bad);
  const std::string negative = Replaced(DemoText(), "seed: 7", "seeds: {truth: -3}");
  EXPECT_TRUE(Contains(ParseError(negative), "scenario.seeds.truth"));
}

}  // namespace
}  // namespace twin
