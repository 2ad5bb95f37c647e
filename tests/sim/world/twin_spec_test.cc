#include "sim/world/twin_spec.h"

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "tests/calib/test_models.h"

namespace twin {
namespace {

const std::string kWhere = "cell.yaml";

Matrix3 RotX(double deg) { return Eigen::AngleAxisd(DegToRad(deg), Vector3::UnitX()).matrix(); }
Matrix3 RotY(double deg) { return Eigen::AngleAxisd(DegToRad(deg), Vector3::UnitY()).matrix(); }
Matrix3 RotZ(double deg) { return Eigen::AngleAxisd(DegToRad(deg), Vector3::UnitZ()).matrix(); }

/// A valid cell: two Reinovo-like arms on the floor, 1.2 m apart and facing each other.
TwinSpec ValidSpec() {
  TwinSpec spec;
  for (int i = 0; i < kMaxRobots; ++i) {
    spec.robots[i].model = testing::ReinovoLikeModel();
    spec.robots[i].model.name = i == 0 ? "r1" : "r2";
  }
  spec.robots[1].X_WB.translation() = Vector3(1.2, 0.0, 0.0);
  spec.robots[1].X_WB.linear() = RotZ(180);
  spec.robots[0].q_initial << 0, 0.5, -0.5, 0, 1.5, 0;
  spec.camera.robot = 0;
  spec.board.robot = 1;
  EffectSpec e;
  e.type = "transmission_error";
  e.robot = 1;
  e.joint = 2;
  e.params["amplitude_deg"] = 0.02;
  spec.effects.push_back(e);
  return spec;
}

::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' lacks '" << part << "'";
}

/// The message of the InputError that validating `spec` throws (a test failure if none).
std::string ErrorOf(const TwinSpec& spec) {
  try {
    ValidateTwinSpec(spec, kWhere);
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), kWhere);
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return "";
}

/// ErrorOf(ValidSpec() changed by `change`).
std::string ErrorAfter(const std::function<void(TwinSpec*)>& change) {
  TwinSpec spec = ValidSpec();
  change(&spec);
  return ErrorOf(spec);
}

bool Valid(const std::function<void(TwinSpec*)>& change) {
  TwinSpec spec = ValidSpec();
  change(&spec);
  try {
    ValidateTwinSpec(spec, kWhere);
  } catch (const InputError& e) {
    ADD_FAILURE() << e.what();
    return false;
  }
  return true;
}

TEST(TwinSpecTest, InstallationNames) {
  EXPECT_STREQ(ToString(Installation::kFloor), "floor");
  EXPECT_STREQ(ToString(Installation::kWall), "wall");
  EXPECT_STREQ(ToString(Installation::kCeiling), "ceiling");
}

TEST(TwinSpecTest, ValidSpecPasses) {
  EXPECT_NO_THROW(ValidateTwinSpec(ValidSpec(), kWhere));
}

TEST(TwinSpecTest, DefaultsOfTheStructsAreValid) {
  // Default intrinsics, board, tips and physics with the two robots placed apart.
  TwinSpec spec;
  for (RobotSpec& r : spec.robots) r.model = testing::ReinovoLikeModel();
  spec.robots[1].X_WB.translation() = Vector3(1.2, 0.0, 0.0);
  EXPECT_NO_THROW(ValidateTwinSpec(spec, kWhere));
}

// ---- Board ----

TEST(TwinSpecErrorTest, NegativeSquareSize) {
  const std::string msg = ErrorAfter([](TwinSpec* s) { s->board.square_m = -0.02; });
  EXPECT_TRUE(Contains(msg, kWhere + ": board.square_m must be a finite number > 0 m, got -0.02"));
}

TEST(TwinSpecErrorTest, NonFiniteSquareSize) {
  const std::string msg = ErrorAfter(
      [](TwinSpec* s) { s->board.square_m = std::numeric_limits<double>::quiet_NaN(); });
  EXPECT_TRUE(Contains(msg, "board.square_m must be a finite number > 0 m, got nan"));
}

TEST(TwinSpecErrorTest, BoardNeedsTwoSquaresEachWay) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.squares_y = 1; }),
                       "board.squares_y must be from 2 to 30, got 1"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.squares_x = 0; }),
                       "board.squares_x must be from 2 to 30, got 0"));
}

TEST(TwinSpecErrorTest, BoardMarginThicknessMass) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.margin_m = -0.001; }),
                       "board.margin_m must be a finite number >= 0 m, got -0.001"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.thickness_m = 0.0; }),
                       "board.thickness_m must be a finite number > 0 m, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.mass_kg = -1.0; }),
                       "board.mass_kg must be a finite number >= 0 kg, got -1"));
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->board.margin_m = 0.0; }));
}

TEST(TwinSpecErrorTest, BoardMountMustBeRigid) {
  const std::string msg =
      ErrorAfter([](TwinSpec* s) { s->board.X_FT.linear() = 1.01 * Matrix3::Identity(); });
  EXPECT_TRUE(Contains(msg, "board.X_FT must be a rigid transform"));
  EXPECT_TRUE(Contains(msg, "|R^T R - I| = "));
  const std::string mirrored =
      ErrorAfter([](TwinSpec* s) { s->board.X_FT.linear() = -Matrix3::Identity(); });
  EXPECT_TRUE(Contains(mirrored, "board.X_FT must be a rigid transform"));
  EXPECT_TRUE(Contains(mirrored, "det R = -1"));
}

// ---- Camera ----

TEST(TwinSpecErrorTest, ZeroFocalLength) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.fx = 0.0; }),
                       "camera.intrinsics.fx must be a finite number > 0 px, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->camera.intrinsics.fy = std::numeric_limits<double>::infinity();
                       }),
                       "camera.intrinsics.fy must be a finite number > 0 px, got inf"));
}

TEST(TwinSpecErrorTest, ImageSize) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.width = 0; }),
                       "camera.intrinsics.width must be from 16 to 4096, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.height = 5000; }),
                       "camera.intrinsics.height must be from 16 to 4096, got 5000"));
}

TEST(TwinSpecErrorTest, PrincipalPointOutsideImage) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.cx = 1100; }),
                       "camera.intrinsics.cx must lie inside the image, [-0.5, 1023.5] px, "
                       "got 1100"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.cy = -3; }),
                       "camera.intrinsics.cy must lie inside the image, [-0.5, 767.5] px, "
                       "got -3"));
  // The edges of the outermost pixels are still inside.
  EXPECT_TRUE(Valid([](TwinSpec* s) {
    s->camera.intrinsics.cx = -0.5;
    s->camera.intrinsics.cy = 767.5;
  }));
}

TEST(TwinSpecErrorTest, DistortionMustBeFinite) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->camera.distortion.p2 = std::numeric_limits<double>::quiet_NaN();
                       }),
                       "camera.distortion.p2 must be a finite number, got nan"));
}

TEST(TwinSpecErrorTest, MsaaSamples) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.msaa_samples = 3; }),
                       "camera.msaa_samples must be 0, 1, 2, 4 or 8"));
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->camera.msaa_samples = 0; }));
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->camera.msaa_samples = 8; }));
}

TEST(TwinSpecErrorTest, ClippingPlanes) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.near_m = 0.0; }),
                       "camera.near_m must be a finite number > 0 m, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->camera.near_m = 0.5;
                         s->camera.far_m = 0.5;
                       }),
                       "camera.far_m must be beyond camera.near_m = 0.5 m, got 0.5"));
}

TEST(TwinSpecErrorTest, HandEyeMustBeRigid) {
  const std::string msg = ErrorAfter([](TwinSpec* s) {
    s->camera.X_FC.translation().x() = std::numeric_limits<double>::quiet_NaN();
  });
  EXPECT_TRUE(Contains(msg, "camera.X_FC must be a finite transform"));
}

// ---- Robots ----

TEST(TwinSpecErrorTest, CameraAndBoardOnTheSameRobot) {
  const std::string msg = ErrorAfter([](TwinSpec* s) { s->board.robot = 0; });
  EXPECT_TRUE(Contains(msg, "board.robot must differ from camera.robot"));
  EXPECT_TRUE(Contains(msg, "got both 0"));
}

TEST(TwinSpecErrorTest, RobotIndexOutOfRange) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.robot = 2; }),
                       "camera.robot must be from 0 to 1, got 2"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.robot = -1; }),
                       "board.robot must be from 0 to 1, got -1"));
}

TEST(TwinSpecErrorTest, InitialJointsOutOfLimits) {
  // Joint 3 of the Reinovo-like model travels [-140, 140] deg.
  const std::string msg =
      ErrorAfter([](TwinSpec* s) { s->robots[1].q_initial(2) = DegToRad(150.0); });
  EXPECT_TRUE(Contains(msg, "robots[1].q_initial[2] must be within joint 3's limits "
                            "[-140, 140] deg, got 150 deg"));
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->robots[1].q_initial(2) = DegToRad(140.0); }));
}

TEST(TwinSpecErrorTest, NonFiniteInitialJoint) {
  const std::string msg = ErrorAfter([](TwinSpec* s) {
    s->robots[0].q_initial(5) = std::numeric_limits<double>::quiet_NaN();
  });
  EXPECT_TRUE(Contains(msg, "robots[0].q_initial[5] must be a finite number, got nan"));
}

TEST(TwinSpecErrorTest, InvalidModelIsNamed) {
  const std::string msg = ErrorAfter([](TwinSpec* s) {
    s->robots[1].model.links[3].limits = {1.0, -1.0};
  });
  EXPECT_TRUE(Contains(msg, "robots[1].model (r2): link 4 (link4): joint lower limit 1 rad "
                            "must be below upper limit -1 rad"));
}

TEST(TwinSpecErrorTest, BasePoseMustBeRigid) {
  const std::string msg =
      ErrorAfter([](TwinSpec* s) { s->robots[1].X_WB.linear() *= 2.0; });
  EXPECT_TRUE(Contains(msg, "robots[1].X_WB must be a rigid transform"));
}

TEST(TwinSpecErrorTest, WallInstallationWithVerticalBase) {
  const std::string msg =
      ErrorAfter([](TwinSpec* s) { s->robots[0].installation = Installation::kWall; });
  EXPECT_TRUE(Contains(msg, "robots[0].installation is wall, but the base z axis in the "
                            "world is (0, 0, 1), 90 deg above horizontal; expected within "
                            "5 deg of horizontal"));
}

TEST(TwinSpecErrorTest, CeilingInstallationWithUprightBase) {
  const std::string msg =
      ErrorAfter([](TwinSpec* s) { s->robots[1].installation = Installation::kCeiling; });
  EXPECT_TRUE(Contains(msg, "robots[1].installation is ceiling"));
  EXPECT_TRUE(Contains(msg, "expected within 5 deg of -z (world down)"));
}

TEST(TwinSpecErrorTest, FloorInstallationToleratesFiveDegrees) {
  // Tilted 4.9 deg: still a floor robot; 5.1 deg: not any more.
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->robots[0].X_WB.linear() = RotX(4.9); }));
  const std::string msg =
      ErrorAfter([](TwinSpec* s) { s->robots[0].X_WB.linear() = RotY(-5.1); });
  EXPECT_TRUE(Contains(msg, "robots[0].installation is floor"));
  EXPECT_TRUE(Contains(msg, "84.9 deg above horizontal; expected within 5 deg of +z"));
}

TEST(TwinSpecTest, WallAndCeilingInstallationsMatchTheirBases) {
  // Gan et al. 2014, Table 1: a wall robot has its base z horizontal (ZYZ (180, 90, 180)),
  // a ceiling robot has it pointing down (ZYZ (0, 180, 0)).
  EXPECT_TRUE(Valid([](TwinSpec* s) {
    s->robots[1].installation = Installation::kWall;
    s->robots[1].X_WB.linear() = RotZ(180) * RotY(90) * RotZ(180);
  }));
  EXPECT_TRUE(Valid([](TwinSpec* s) {
    s->robots[1].installation = Installation::kCeiling;
    s->robots[1].X_WB.translation().z() = 1.5;
    s->robots[1].X_WB.linear() = RotY(180);
  }));
  EXPECT_TRUE(Valid([](TwinSpec* s) {
    s->robots[0].installation = Installation::kWall;
    s->robots[0].X_WB.linear() = RotX(-94.0);  // 4 deg below horizontal
  }));
}

// ---- Tips, physics, effects ----

TEST(TwinSpecErrorTest, TipDimensions) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->tips[1].radius_m = -0.004; }),
                       "tips[1].radius_m must be a finite number > 0 m, got -0.004"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->tips[0].length_m = 0.0; }),
                       "tips[0].length_m must be a finite number > 0 m, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->tips[0].X_FTip.linear() *= 0.5; }),
                       "tips[0].X_FTip must be a rigid transform"));
}

TEST(TwinSpecErrorTest, PhysicsValues) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.timestep_s = 0.0; }),
                       "physics.timestep_s must be a finite number > 0 s, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.stiffness = -2.5; }),
                       "physics.stiffness must be a finite number > 0 N m/rad, got -2.5"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.armature = 0.0; }),
                       "physics.armature must be a finite number > 0 kg m^2, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.max_joint_speed = 0.0; }),
                       "physics.max_joint_speed must be a finite number > 0 rad/s, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.settle_speed = -1.0; }),
                       "physics.settle_speed must be a finite number > 0 rad/s, got -1"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.settle_steps = 0; }),
                       "physics.settle_steps must be >= 1, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.max_steps = 10; }),
                       "physics.max_steps must be >= physics.settle_steps = 20"));
}

// ---- Plausibility limits (issue 14): finite but absurd values, each refused with the limit.

TEST(TwinSpecPlausibilityTest, CameraIntrinsicsAndLens) {
  // fx of 1e-9 or 1e12 px: fields of view of 180 deg or nothing.
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.fx = 1e-9; }),
                       "camera.intrinsics.fx must be in [51.2, 51200] px (0.05 to 50 times"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.fx = 1e12; }),
                       "fields of view from 175 to 1.1 deg"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.intrinsics.fy = 2000; }),
                       "camera.intrinsics.fy must be in [0.5, 2] x fx"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.distortion.k1 = 50; }),
                       "camera.distortion.k1 must be in [-10, 10]"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.distortion.p1 = 0.5; }),
                       "camera.distortion.p1 must be in [-0.1, 0.1]"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.near_m = 1e-6; }),
                       "camera.near_m must be in [0.001, 100] m"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->camera.far_m = 1000; }),
                       "camera.far_m must be in [0.001, 100] m"));
}

TEST(TwinSpecPlausibilityTest, BoardSquaresMustBeVisible) {
  // Squares of 1 m never fit the view at 2 m; squares of 1 um image to less than a pixel.
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.square_m = 1.0; }),
                       "larger than the camera's view at 2 m"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.square_m = 1e-6; }),
                       "must image to at least one pixel"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.squares_x = 40; }),
                       "board.squares_x must be from 2 to 30"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.mass_kg = 500; }),
                       "board.mass_kg must be in [0, 20] kg"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->board.thickness_m = 2; }),
                       "board.thickness_m must be in [0, 0.1] m"));
}

TEST(TwinSpecPlausibilityTest, FlangeToolsAreOnTheFlangeAndNotInsideIt) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->camera.X_FC.translation() = Vector3(0.0, 0.01, -0.005);
                       }),
                       "camera.X_FC puts the camera's optical centre at (0, 10, -5) mm in the "
                       "flange frame, inside the flange (radius 35 mm"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->board.X_FT.translation() = Vector3(0.0, 0.0, -0.02);
                       }),
                       "board.X_FT puts the board's feature point"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->tips[1].X_FTip.translation() = Vector3(0.01, 0.0, -0.03);
                       }),
                       "tips[1].X_FTip puts the tip point"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->camera.X_FC.translation() = Vector3(1000, 0, 0);
                       }),
                       "camera.X_FC translation must be at most 1 m long"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->tips[0].length_m = 5; }),
                       "tips[0].length_m must be in [0, 1] m"));
  // On the face, beside the flange, or in front of it: fine.
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->camera.X_FC.translation() = Vector3(0.0, 0.0, 0.0); }));
  EXPECT_TRUE(Valid([](TwinSpec* s) { s->camera.X_FC.translation() = Vector3(0.085, 0, -0.03); }));
}

TEST(TwinSpecPlausibilityTest, BasesWithinACell) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->robots[0].X_WB.translation() = Vector3(1e6, 0, 0);
                       }),
                       "robots[0].X_WB translation must be at most 100 m long"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->robots[1].X_WB.translation() = Vector3(50, 0, 0);
                       }),
                       "puts robot 2's base 50 m from robot 1's"));
}

TEST(TwinSpecPlausibilityTest, PhysicsRunsEnd) {
  // max_steps: 1e9 with a tiny settle speed never ends: both are bounded.
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.max_steps = 1000000000; }),
                       "physics.max_steps must be from 1 to 1000000"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.settle_speed = 1e-300; }),
                       "physics.settle_speed must be in [1e-12, 1] rad/s"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->physics.max_steps = 1000000;
                         s->physics.timestep_s = 0.005;
                       }),
                       "at most 600 s of simulated time per move"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.timestep_s = 0.5; }),
                       "physics.timestep_s must be in [1e-05, 0.01] s"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->physics.stiffness = 1e12; }),
                       "physics.stiffness must be in [10, 1e+08] N m/rad"));
}

TEST(TwinSpecErrorTest, EffectIndices) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->effects[0].joint = 6; }),
                       "effects[0].joint must be from -1 to 5, got 6"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->effects[0].robot = 2; }),
                       "effects[0].robot must be from -1 to 1, got 2"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->effects[0].type.clear(); }),
                       "effects[0].type must name an effect type"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) {
                         s->effects[0].params["amplitude_deg"] =
                             std::numeric_limits<double>::infinity();
                       }),
                       "effects[0].params.amplitude_deg must be a finite number, got inf"));
}

// ---- A one-robot cell (a laser-tracker cell): no camera, board or second robot ----

/// ValidSpec's robot 1 alone with a tracker on it; camera and board left as the two-robot
/// cell had them, to show they are not looked at.
TwinSpec OneRobotSpec() {
  TwinSpec spec = ValidSpec();
  spec.num_robots = 1;
  spec.effects[0].robot = 0;
  spec.tracker.present = true;
  spec.tracker.robot = 0;
  spec.tracker.X_WT.translation() = Vector3(-2.0, -0.4, 0.9);
  spec.tracker.p_FR = Vector3(0.04, -0.03, 0.08);
  return spec;
}

TEST(TwinSpecOneRobotTest, ValidWithoutCameraAndBoard) {
  TwinSpec spec = OneRobotSpec();
  EXPECT_FALSE(spec.HasCameraAndBoard());
  EXPECT_NO_THROW(ValidateTwinSpec(spec, kWhere));
  // Camera, board and a second robot's entries are not checked: each value below is refused
  // by a two-robot cell and passes here.
  const std::vector<std::pair<std::string, std::function<void(TwinSpec*)>>> unused = {
      {"camera.intrinsics.fx", [](TwinSpec* s) { s->camera.intrinsics.fx = 0.0; }},
      {"board.square_m", [](TwinSpec* s) { s->board.square_m = -1.0; }},
      {"board.robot must differ", [](TwinSpec* s) { s->camera.robot = s->board.robot = 1; }},
      {"robots[1].X_WB",
       [](TwinSpec* s) { s->robots[1].X_WB.translation() = Vector3(500, 0, 0); }},
      {"tips[1].length_m", [](TwinSpec* s) { s->tips[1].length_m = -1.0; }}};
  for (const auto& [field, change] : unused) {
    TwinSpec one = OneRobotSpec();
    change(&one);
    EXPECT_NO_THROW(ValidateTwinSpec(one, kWhere)) << field;
    one.num_robots = 2;
    EXPECT_TRUE(Contains(ErrorOf(one), field));
  }
}

TEST(TwinSpecOneRobotTest, RefusesAnIntrinsicsTargetAndIndicesOfASecondRobot) {
  TwinSpec spec = OneRobotSpec();
  spec.intrinsics_target = spec.board;
  EXPECT_TRUE(Contains(ErrorOf(spec), "intrinsics_target must be absent on a one-robot cell"));
  spec = OneRobotSpec();
  spec.tracker.robot = 1;
  EXPECT_TRUE(Contains(ErrorOf(spec), "tracker.robot must be from 0 to 0, got 1"));
  spec = OneRobotSpec();
  spec.effects[0].robot = 1;
  EXPECT_TRUE(Contains(ErrorOf(spec), "effects[0].robot must be from -1 to 0, got 1"));
  spec = OneRobotSpec();
  spec.robots[0].q_initial(1) = 10.0;  // still checked: the cell's own robot
  EXPECT_TRUE(Contains(ErrorOf(spec), "robots[0].q_initial[1]"));
}

TEST(TwinSpecErrorTest, NumberOfRobotsIsOneOrTwo) {
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->num_robots = 0; }),
                       "num_robots must be from 1 to 2, got 0"));
  EXPECT_TRUE(Contains(ErrorAfter([](TwinSpec* s) { s->num_robots = 3; }),
                       "num_robots must be from 1 to 2, got 3"));
}

}  // namespace
}  // namespace twin
