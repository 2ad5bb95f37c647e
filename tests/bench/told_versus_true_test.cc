// Told versus true (issue 14, item 1): what the estimator is told comes from the scenario's
// told values only, never from the twin's truth. The estimator's inputs are built from a
// scenario (scenarios/workflow_dual.yaml: both procedures), then from the same scenario with
// every truth-only value changed; they must be identical. A control changes a told value and
// must see the inputs change, so the comparison is not vacuous.
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "bench/io/calibration_config.h"
#include "bench/io/scenario.h"
#include "bench/runs/handclasp_run.h"
#include "calib/common/errors.h"
#include "calib/model/parameters.h"
#include "calib/procedures/handclasp_procedure.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {

using testing::ReadFile;
using testing::Replaced;

const std::string kScenarioDir = std::string(TWIN_SOURCE_DIR) + "/scenarios";

void Put(std::ostream& os, const std::string& name, const Transform& X) {
  os << name << ":";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) os << " " << X.matrix()(r, c);
  }
  os << "\n";
}

void Put(std::ostream& os, const std::string& name, const KinematicModel& m) {
  os << name << " " << m.name << " joints " << m.num_joints() << " parameters";
  const ParameterVector p = GetParameters(m);
  for (int i = 0; i < p.size(); ++i) os << " " << p(i);
  for (int i = 0; i < m.num_joints(); ++i) {
    os << " limits " << m.links[i].limits.lower << " " << m.links[i].limits.upper;
  }
  os << "\n";
  Put(os, name + ".X_BL0", m.X_BL0);
  Put(os, name + ".X_LtE", m.X_LtE);
}

// Every estimator input a scenario yields, at full precision: the optical-axis calibration's
// CellKnowledge and options, and the handclasp's told layout, told tips (as the pendants' tip
// models on the nominal kinematics), points and options.
std::string EstimatorInputs(const Scenario& sc) {
  std::ostringstream os;
  os << std::setprecision(17);
  const CalibrationConfig c = ParseCalibrationConfig(sc);
  const CellKnowledge& k = c.knowledge;
  for (int i = 0; i < 2; ++i) Put(os, "nominal" + std::to_string(i), k.nominal[i]);
  Put(os, "rough X_B1B2", k.X_B1B2);
  Put(os, "rough X_FC", k.X_FC);
  Put(os, "board X_FT", k.X_FT);
  os << "board " << k.board.squares_x << " " << k.board.squares_y << " " << k.board.square_m
     << "\n";
  if (k.intrinsics_target) {
    os << "intrinsics target " << k.intrinsics_target->squares_x << " "
       << k.intrinsics_target->squares_y << " " << k.intrinsics_target->square_m << "\n";
  }
  const OpticalAxisOptions& o = c.options;
  os << "robots";
  for (int r : o.robots) os << " " << r;
  os << "\nintrinsics_views " << o.intrinsics_views << " calibration_axes "
     << o.calibration_axes << " split " << static_cast<int>(o.split) << " refit "
     << o.refit_all_axes << " carry " << o.carry_correction << " predict " << o.predict_axis_start
     << " kept_images "
     << o.kept_images << " intrinsics fix_k3 " << o.intrinsics.fix_k3 << " pinhole "
     << o.intrinsics.fix_all_distortion << "\n";
  const PosePlannerOptions& p = o.planner;
  os << "planner " << p.num_axes << " " << p.positions_per_axis << " " << p.swarm_size << " "
     << p.iterations << " " << p.runs << " " << p.min_joint_limit_distance << " "
     << p.min_singular_value << " " << p.max_visibility_angle << " " << p.min_distance << " "
     << p.max_distance << " " << p.planning_max_distance << " " << p.distance_step << " "
     << p.camera_reach << " " << p.camera_height << " " << p.seed << "\n";
  os << "servo " << o.servo.tolerance_px << " " << o.servo.max_iterations << " "
     << o.servo.gain << "\n";
  // The diagnosis: the told payload and its settings (stated noise, candidates, seed).
  const DiscoveryOptions& d = c.discovery;
  os << "board mass " << c.board_mass_kg << " diagnosis " << c.diagnosis.enabled << " "
     << d.alpha << " " << d.min_gain_percent << " " << d.max_effects << " " << d.folds << " "
     << d.axis_set.sigma_perpendicular << " " << d.axis_set.sigma_depth << " "
     << d.joint_sigma_rad << " " << d.seed << " candidates " << d.candidates.size() << "\n";

  const HandclaspConfig h = ParseHandclaspConfig(sc);
  Put(os, "handclasp layout", h.rough_X_B1B2);
  for (int i = 0; i < 2; ++i) {
    Put(os, "told tip" + std::to_string(i), h.told_X_FTip[i]);
    Put(os, "pendant tip model" + std::to_string(i),
        WithTipTool(sc.twin.robots[i].model, h.told_X_FTip[i]));
  }
  os << "points " << h.auto_points;
  for (const Vector3& q : h.points_B1) os << " " << q.transpose();
  os << "\nconstraint " << ToString(h.constraint) << " tips identified "
     << h.calibrated_tip_identification << "\n";
  // The estimator's own randomness (intrinsics views, servo IK restarts, the teaching's IK):
  // the estimator seed, which TrueChanged() leaves while it changes the truth seed.
  os << "estimator seed " << sc.seeds.estimator << " intrinsics " << o.seed << " servo ik "
     << o.servo.ik_seed << "\n";
  return os.str();
}

// The scenario with an intrinsics target: the cell has one (twin side, before the effects) and
// the estimator is told its drawing.
std::string WithTarget(std::string t) {
  t = Replaced(t, "  effects:\n",
               "  intrinsics_target: {squares: [14, 10], square_mm: 20, margin_mm: 10, "
               "thickness_mm: 5, mass_kg: 0.6}\n  effects:\n");
  return Replaced(t, "    board_square_mm: 20\n",
                  "    board_square_mm: 20\n    intrinsics_target: {squares: [14, 10], "
                  "square_mm: 20}\n");
}

Scenario Parse(const std::string& text) {
  return ParseScenario(text, "told_versus_true.yaml", kScenarioDir);
}

// scenarios/workflow_dual.yaml with every truth-only value changed (all still valid): the
// true base layout and world pose, hand-eye, intrinsics, distortion, resolution and rendering,
// the board as built and mounted, the tips as built, the physics, every effect's magnitude
// plus an undeclared effect, the simulated operator's accuracy, and the bench's scoring.
std::string TrueChanged(std::string t) {
  t = Replaced(t, "base: {xyz_mm: [0, 0, 0], rpy_deg: [0, 0, 0]}",
               "base: {xyz_mm: [15, -7, 3], rpy_deg: [0.4, -0.3, 2]}");
  t = Replaced(t, "base_from_robot1: {xyz_mm: [1203.2, -2.6, 0.8], zyz_deg: [179.7, 0.2, -0.1]}",
               "base_from_robot1: {xyz_mm: [1211.5, 6.3, -2.1], zyz_deg: [178.9, 0.5, 0.4]}");
  t = Replaced(t, "hand_eye: {xyz_mm: [62.1, -58.4, -24.3], rpy_deg: [0.8, -0.6, 1.1]}",
               "hand_eye: {xyz_mm: [58.0, -61.9, -27.5], rpy_deg: [-0.9, 0.7, -1.3]}");
  t = Replaced(t, "resolution: [1024, 768]", "resolution: [1280, 960]");
  t = Replaced(t, "fx: 834.31", "fx: 1040.7");
  t = Replaced(t, "fy: 833.38", "fy: 1043.2");
  t = Replaced(t, "cx: 513.56", "cx: 650.1");
  t = Replaced(t, "cy: 403.95", "cy: 470.3\n    distortion: [-0.05, 0.01, 0.0005, -0.0003, 0]");
  t = Replaced(t, "msaa: 4", "msaa: 2\n    near_mm: 25\n    far_mm: 4000");
  t = Replaced(t, "squares: [4, 4]", "squares: [6, 6]");
  t = Replaced(t, "square_mm: 20\n    margin_mm: 10\n    thickness_mm: 4\n    mass_kg: 0.2",
               "square_mm: 18\n    margin_mm: 12\n    thickness_mm: 5\n    mass_kg: 0.3");
  t = Replaced(t, "  intrinsics_target: {squares: [14, 10], square_mm: 20, margin_mm: 10, "
                  "thickness_mm: 5, mass_kg: 0.6}",
               "  intrinsics_target: {squares: [12, 10], square_mm: 22, margin_mm: 14, "
               "thickness_mm: 6, mass_kg: 0.7, mount: {xyz_mm: [80.6, 0.4, 42], "
               "rpy_deg: [0.2, 0, 0]}}");
  t = Replaced(t, "mount: {xyz_mm: [80, 0, 40], rpy_deg: [0, 0, 0]}",
               "mount: {xyz_mm: [81.2, -0.7, 41.1], rpy_deg: [0.3, -0.2, 0.5]}");
  t = Replaced(t, "r1: {xyz_mm: [-60, 60, 100], rpy_deg: [0, 0, 0], length_mm: 90, radius_mm: 4}",
               "r1: {xyz_mm: [-60.4, 60.3, 100.8], rpy_deg: [0.2, 0, 0], length_mm: 91, "
               "radius_mm: 3.5}");
  t = Replaced(t, "r2: {xyz_mm: [-150, 0, 20], rpy_deg: [0, -90, 0], length_mm: 130, radius_mm: 4}",
               "r2: {xyz_mm: [-149.2, 0.6, 20.4], rpy_deg: [0, -89.7, 0.2], length_mm: 131, "
               "radius_mm: 4.5}");
  t = Replaced(t, "operator_error_mm: 0.5", "operator_error_mm: 0.8");
  t = Replaced(t, "calibrated_operator_error_mm: 0.1", "calibrated_operator_error_mm: 0.05");
  t = Replaced(t, "sigma_length_mm: 2.0\n      sigma_angle_deg: 0.25",
               "sigma_length_mm: 1.5\n      sigma_angle_deg: 0.3\n"
               "      link3.alpha_deg: 0.1");
  t = Replaced(t, "sigma_deg: 0.0005", "sigma_deg: 0.001");
  t = Replaced(t, "sigma_levels: 1.0",
               "sigma_levels: 2.0\n    - type: transmission_error\n      declared: false\n"
               "      robot: r2\n      joint: 3\n      amplitude_deg: 0.01\n      harmonic: 2");
  t = Replaced(t, "  effects:\n",
               "  physics:\n    timestep_s: 0.0015\n    stiffness_Nm_per_rad: 2.0e5\n"
               "    armature_kgm2: 0.12\n    settle_steps: 25\n    max_steps: 30000\n"
               "  effects:\n");
  t = Replaced(t, "\n  seed: 2019\n", "\n  seeds: {truth: 2024, estimator: 2019}\n");
  t = Replaced(t, "scoring: {configurations: 200, seed: 1}",
               "scoring: {configurations: 150, seed: 5}");
  return t;
}

TEST(ToldVersusTrue, EstimatorInputsDoNotDependOnAnyTruthOnlyValue) {
  const std::string text = WithTarget(ReadFile(kScenarioDir + "/workflow_dual.yaml"));
  const Scenario original = Parse(text);
  const Scenario changed = Parse(TrueChanged(text));
  // The change reached the truth (the comparison below is not vacuous) ...
  EXPECT_NE(original.twin.camera.intrinsics.fx, changed.twin.camera.intrinsics.fx);
  EXPECT_NE(original.twin.board.X_FT.translation(), changed.twin.board.X_FT.translation());
  EXPECT_NE(original.twin.board.square_m, changed.twin.board.square_m);
  EXPECT_NE(original.twin.tips[0].X_FTip.translation(), changed.twin.tips[0].X_FTip.translation());
  EXPECT_NE(original.twin.robots[1].X_WB.translation(), changed.twin.robots[1].X_WB.translation());
  EXPECT_NE(original.twin.camera.X_FC.translation(), changed.twin.camera.X_FC.translation());
  EXPECT_EQ(changed.twin.effects.size(), original.twin.effects.size() + 1);
  ASSERT_TRUE(original.twin.intrinsics_target && changed.twin.intrinsics_target);
  EXPECT_NE(original.twin.intrinsics_target->squares_x, changed.twin.intrinsics_target->squares_x);
  EXPECT_NE(original.twin.intrinsics_target->X_FT.translation(),
            changed.twin.intrinsics_target->X_FT.translation());
  // ... and none of it reached the estimator.
  EXPECT_EQ(EstimatorInputs(original), EstimatorInputs(changed));
}

TEST(ToldVersusTrue, ChangingAToldValueChangesTheEstimatorInputs) {
  const std::string text = WithTarget(ReadFile(kScenarioDir + "/workflow_dual.yaml"));
  const std::string inputs = EstimatorInputs(Parse(text));
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"rough_hand_eye: {xyz_mm: [60, -60, -26]", "rough_hand_eye: {xyz_mm: [61, -60, -26]"},
           {"board_mount: {xyz_mm: [80, 0, 40]", "board_mount: {xyz_mm: [80, 0, 41]"},
           {"board_square_mm: 20", "board_square_mm: 21"},
           {"board_square_mm: 20", "board_square_mm: 20\n    intrinsics_distortion: none"},
           {"intrinsics_target: {squares: [14, 10], square_mm: 20}",
            "intrinsics_target: {squares: [14, 10], square_mm: 21}"},
           {"r1: {xyz_mm: [-60, 60, 100], rpy_deg: [0, 0, 0]}",
            "r1: {xyz_mm: [-60, 60, 101], rpy_deg: [0, 0, 0]}"},
           {"rough_base_from_robot1: {xyz_mm: [1200, 0, 0], zyz_deg: [180, 0, 0]}\n    tips",
            "rough_base_from_robot1: {xyz_mm: [1201, 0, 0], zyz_deg: [180, 0, 0]}\n    tips"}}) {
    EXPECT_NE(EstimatorInputs(Parse(Replaced(text, from, to))), inputs) << to;
  }
}

TEST(ToldVersusTrue, EveryShippedProcedureScenarioStatesItsToldValues) {
  // A missing told value is an error, never the truth: drop each from a copy and expect the
  // key named.
  const std::string wf = ReadFile(kScenarioDir + "/workflow_dual.yaml");
  for (const std::string key : {"board_mount", "board_squares", "board_square_mm",
                                "rough_hand_eye"}) {
    const std::size_t at = wf.find("    " + key + ":");
    ASSERT_NE(at, std::string::npos) << key;
    std::string t = wf;
    t.erase(at, t.find('\n', at) + 1 - at);
    try {
      ParseCalibrationConfig(Parse(t));
      ADD_FAILURE() << "no error without " << key;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("missing required key '" + key + "'"),
                std::string::npos)
          << e.what();
    }
  }
  const std::string hc = ReadFile(kScenarioDir + "/gan2014_floor_floor.yaml");
  const std::size_t at = hc.find("    rough_base_from_robot1:");
  ASSERT_NE(at, std::string::npos);
  std::string t = hc;
  t.erase(at, t.find('\n', at) + 1 - at);
  try {
    ParseHandclaspConfig(Parse(t));
    ADD_FAILURE() << "no error without the told layout";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rough_base_from_robot1"), std::string::npos)
        << e.what();
  }
  try {
    ParseHandclaspConfig(
        Parse(Replaced(hc, "      r2: {xyz_mm: [0, 0, 200], rpy_deg: [0, 0, 0]}\n", "")));
    ADD_FAILURE() << "no error without robot 2's told tip";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing the told tip of robot 'r2'"),
              std::string::npos)
        << e.what();
  }
}

// The planner's run selection from the scenario: the paper's by default, the predicted error
// when asked, and a clear error naming the key and the value otherwise.
TEST(ToldVersusTrue, PlanningRunSelectionIsReadFromTheScenario) {
  const std::string paper = ReadFile(kScenarioDir + "/paper_reinovo.yaml");
  const std::string seed_line = "      seed: 1\n";
  ASSERT_NE(paper.find(seed_line), std::string::npos);
  EXPECT_EQ(ParseCalibrationConfig(Parse(paper)).options.planner.select_run,
            PosePlannerOptions::RunSelection::kBestFitness);
  const std::string predicted =
      Replaced(paper, seed_line, seed_line + "      select_run: predicted_error\n");
  EXPECT_EQ(ParseCalibrationConfig(Parse(predicted)).options.planner.select_run,
            PosePlannerOptions::RunSelection::kPredictedError);
  try {
    ParseCalibrationConfig(
        Parse(Replaced(paper, seed_line, seed_line + "      select_run: newest\n")));
    ADD_FAILURE() << "no error for an unknown run selection";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("select_run"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'newest'"), std::string::npos) << e.what();
  }
}

// The planner's IK from the scenario: iterative by default (its paired study did not accept
// the closed form as the default), the closed form when asked, and an error naming the key and
// the value otherwise.
TEST(ToldVersusTrue, PlannerIkIsReadFromTheScenario) {
  const std::string paper = ReadFile(kScenarioDir + "/paper_reinovo.yaml");
  const std::string seed_line = "      seed: 1\n";
  ASSERT_NE(paper.find(seed_line), std::string::npos);
  EXPECT_FALSE(ParseCalibrationConfig(Parse(paper)).options.planner.closed_form_ik);
  EXPECT_TRUE(ParseCalibrationConfig(
                  Parse(Replaced(paper, seed_line, seed_line + "      ik: closed_form\n")))
                  .options.planner.closed_form_ik);
  EXPECT_FALSE(ParseCalibrationConfig(
                   Parse(Replaced(paper, seed_line, seed_line + "      ik: iterative\n")))
                   .options.planner.closed_form_ik);
  try {
    ParseCalibrationConfig(Parse(Replaced(paper, seed_line, seed_line + "      ik: analytic\n")));
    ADD_FAILURE() << "no error for an unknown IK";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ik"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'analytic'"), std::string::npos) << e.what();
  }
}

// The encoder readings averaged per aligned pose: the paper scenario states 16, a scenario that
// does not state it gets one reading (the paper's), and a count below 1 or a fraction is an
// error naming the key.
TEST(ToldVersusTrue, EncoderReadingsAreReadFromTheScenario) {
  const std::string paper = ReadFile(kScenarioDir + "/paper_reinovo.yaml");
  const std::string stated = ", encoder_readings: 16}";
  ASSERT_NE(paper.find(stated), std::string::npos);
  EXPECT_EQ(ParseCalibrationConfig(Parse(paper)).options.servo.encoder_readings, 16);
  EXPECT_EQ(ParseCalibrationConfig(Parse(Replaced(paper, stated, "}")))
                .options.servo.encoder_readings,
            1);
  for (const char* bad : {"0", "2.5", "-4"}) {
    try {
      ParseCalibrationConfig(
          Parse(Replaced(paper, stated, ", encoder_readings: " + std::string(bad) + "}")));
      ADD_FAILURE() << "no error for encoder_readings " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("encoder_readings"), std::string::npos) << e.what();
    }
  }
}

// The board pose test's level from the scenario: on by default (1e-6), 0 turns it off, a value
// that is not a usable p-value is an error naming the key.
TEST(ToldVersusTrue, BoardPoseTestLevelIsReadFromTheScenario) {
  const std::string paper = ReadFile(kScenarioDir + "/paper_reinovo.yaml");
  const std::string line = "    calibration_axes: 6";
  ASSERT_NE(paper.find(line), std::string::npos);
  EXPECT_DOUBLE_EQ(ParseCalibrationConfig(Parse(paper)).options.board_pose_test_p, 1e-6);
  EXPECT_DOUBLE_EQ(
      ParseCalibrationConfig(Parse(Replaced(paper, line, "    board_pose_test_p: 0\n" + line)))
          .options.board_pose_test_p,
      0.0);
  for (const char* bad : {"0.9", "-1e-3"}) {
    try {
      ParseCalibrationConfig(
          Parse(Replaced(paper, line, "    board_pose_test_p: " + std::string(bad) + "\n" + line)));
      ADD_FAILURE() << "no error for board_pose_test_p " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("board_pose_test_p"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace twin
