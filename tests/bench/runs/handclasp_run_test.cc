// The handclasp base-frame calibration on the twin (bench/runs/handclasp_run.h): exact recovery in
// closed loop with true kinematics, the paper's three set-ups as a seeded batch, the report,
// and the section's input errors.
#include "bench/runs/handclasp_run.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "sim/world/mujoco_handles.h"

namespace twin {
namespace {

const std::string kDir = std::string(TWIN_SOURCE_DIR) + "/scenarios/";
const char* const kSetups[] = {"floor_floor", "floor_ceiling", "floor_wall"};

class HandclaspRunTest : public ::testing::Test {
 protected:
  void SetUp() override { InstallMujocoErrorHandlers(); }
};

Transform FromZyzMm(double x, double y, double z, double a, double b, double c) {
  Transform X = Transform::Identity();
  X.linear() = RotationFromZyz(Vector3(DegToRad(a), DegToRad(b), DegToRad(c)));
  X.translation() = 1e-3 * Vector3(x, y, z);
  return X;
}

// The told values of a set-up's handclasp section (its layout as drawn and the tips by
// drawing, as in scenarios/gan2014_<name>.yaml), as the start of a flow map without its '}'.
std::string ToldSection(const std::string& name) {
  const std::string layout =
      name == "floor_floor"     ? "{xyz_mm: [40, 1475, 50], zyz_deg: [0, 0, -45]}"
      : name == "floor_ceiling" ? "{xyz_mm: [1500, 500, 1500], zyz_deg: [0, 180, 0]}"
                                : "{xyz_mm: [1300, -100, 1390], zyz_deg: [180, 90, -180]}";
  const std::string tip = name == "floor_floor" ? "200" : name == "floor_ceiling" ? "400" : "300";
  return "{rough_base_from_robot1: " + layout + ", tips: {r1: {xyz_mm: [0, 0, " + tip +
         "], rpy_deg: [0, 0, 0]}, r2: {xyz_mm: [0, 0, " + tip + "], rpy_deg: [0, 0, 0]}}";
}

// The paper's set-up with its installation made exact (Table 1's truth rounded onto the
// constraint), so that the constrained solution can be exact too.
Scenario IdealSetup(const std::string& name) {
  Scenario sc = LoadScenario(kDir + "gan2014_" + name + ".yaml");
  Transform X_B1B2;
  if (name == "floor_floor") X_B1B2 = FromZyzMm(37.9, 1476.5, 54.5, 0, 0, -44.5);
  if (name == "floor_ceiling") X_B1B2 = FromZyzMm(1500.1, 500.0, 1499.9, 0, 180, 0.001);
  if (name == "floor_wall") X_B1B2 = FromZyzMm(1303.3, -102.3, 1386.3, 180, 90, -179.997);
  sc.twin.robots[1].X_WB = sc.twin.robots[0].X_WB * X_B1B2;
  sc.handclasp = YamlField{YAML::Load(ToldSection(name) + ", operator_error_mm: 0, "
                                      "coupled_motion: true}"),
                           "scenario.handclasp"};
  return sc;
}

TEST_F(HandclaspRunTest, RecoversTheBaseFrameExactlyWithTrueKinematicsInClosedLoop) {
  // Geometry errors stay on; the controllers use the TRUE models, the operator aligns exactly.
  // Then every contact pair is exact up to the twin's contact tolerance (1e-9 m) and the servo
  // settling between commanded and actual angles (measured below), so both solutions recover
  // X_B1B2. Bound 1e-5 mm (1e-8 m) and 1e-6 deg: measured ~1e-6 mm and ~4e-8 deg (contacts
  // within 1e-9 m, angles settled to ~1e-9 rad); the bound keeps a factor of ~10.
  for (const char* name : kSetups) {
    const Scenario sc = IdealSetup(name);
    TwinCell cell(sc.twin, sc.path);
    const std::array<KinematicModel, 2> truth_models = cell.Truth().models;
    std::ostringstream progress;
    const HandclaspStageResult r = RunHandclaspStage(cell, sc, truth_models, progress);
    ASSERT_TRUE(r.ok()) << name << ": " << r.reason << progress.str();
    // A blocked contact is skipped (on the wall the operator's way in can hit robot 2's own
    // base: 2 of 7 measured); at least 5 must remain for an over-determined, spread set.
    EXPECT_GE(r.procedure.contacts.size(), 5u) << name << progress.str();
    const BaseCalibrationResult& cal = r.procedure.calibration;
    const std::pair<const char*, std::pair<const ScoredBaseFrame*, double>> estimates[] = {
        {"general", {&r.general, cal.rms_residual_general_m}},
        {"constrained", {&r.constrained, cal.rms_residual_constrained_m}}};
    for (const auto& [which, scored] : estimates) {
      const double e_tran = scored.first->kinematic.e_tran_mm;
      const double e_rot = scored.first->kinematic.e_rot_deg;
      std::printf("[ measured ] %s %s exact: e_tran %.3g mm, e_rot %.3g deg, rms %.3g mm\n",
                  name, which, e_tran, e_rot, 1e3 * scored.second);
      EXPECT_LT(e_tran, 1e-5) << name << " " << which;
      EXPECT_LT(e_rot, 1e-6) << name << " " << which;
    }
    // Coupled motion through an exact estimate with exact kinematics: the tips stay together
    // up to the IK tolerance (1e-7 m per robot) and settling; 1e-3 mm keeps a margin of 5.
    ASSERT_TRUE(r.coupled_motion.has_value()) << name;
    ASSERT_TRUE(r.coupled_motion->ok) << r.coupled_motion->reason;
    const double dev = r.coupled_motion->max_deviation_mm;
    std::printf("[ measured ] %s coupled motion max deviation %.3g mm\n", name, dev);
    EXPECT_LT(dev, 1e-3) << name;
  }
}

TEST_F(HandclaspRunTest, ScoresAgainstTheFramesTheKinematicModelsUse) {
  // Explicit link-1 errors on both robots (no other geometry error): robot 1 theta +0.5 deg,
  // d +3 mm; robot 2 theta -0.3 deg, d -2 mm. The pendant models are the TRUE models with link
  // 1's theta and d put back to nominal (what any kinematic calibration ends with: those two
  // are unidentifiable), the operator exact. The handclasp then recovers X_B1'B2' exactly
  // (bounds of the closed-loop exact test above), while the physical X_B1B2 differs by the
  // link-1 offsets: 0.5 + 0.3 deg about z, so the physical e_rot must be near 0.8 deg and the
  // physical e_tran several mm (3 + 2 mm along z, plus the rotation's lever).
  Scenario sc = IdealSetup("floor_floor");
  sc.twin.effects.clear();
  const std::pair<double, double> link1[2] = {{0.5, 3.0}, {-0.3, -2.0}};
  for (int k = 0; k < 2; ++k) {
    EffectSpec e;
    e.type = "geometry_errors";
    e.robot = k;
    e.params = {{"link1.theta_deg", link1[k].first}, {"link1.d_mm", link1[k].second}};
    e.where = "test";
    sc.twin.effects.push_back(e);
  }
  TwinCell cell(sc.twin, sc.path);
  std::array<KinematicModel, 2> pendant = cell.Truth().models;
  for (int k = 0; k < 2; ++k) pendant[k].links[0].dh = [&] {
    DhParameters dh = pendant[k].links[0].dh;
    dh.theta_offset = sc.twin.robots[k].model.links[0].dh.theta_offset;
    dh.d = sc.twin.robots[k].model.links[0].dh.d;
    return dh;
  }();
  // The offset of eq. 2's link-1 part alone: FK_true = X_BB' * FK_pendant for any q.
  const JointVector q = (JointVector(6) << 0.3, -0.4, 0.5, 0.2, -0.6, 0.7).finished();
  for (int k = 0; k < 2; ++k) {
    const Transform lhs = EndPose(cell.Truth().models[k], q);
    const Transform rhs = KinematicBaseOffset(cell.Truth().models[k], pendant[k]) *
                          EndPose(pendant[k], q);
    EXPECT_LT((lhs.matrix() - rhs.matrix()).norm(), 1e-12) << "robot " << k;
  }
  std::ostringstream progress;
  const HandclaspStageResult r = RunHandclaspStage(cell, sc, pendant, progress);
  ASSERT_TRUE(r.ok()) << r.reason << progress.str();
  const std::pair<const char*, const ScoredBaseFrame*> estimates[] = {
      {"general", &r.general}, {"constrained", &r.constrained}};
  for (const auto& [which, scored] : estimates) {
    const double e_tran = scored->kinematic.e_tran_mm, e_rot = scored->kinematic.e_rot_deg;
    const double p_tran = scored->physical.e_tran_mm;
    const double p_rot = scored->physical.e_rot_deg;
    std::printf("[ measured ] %s: kinematic frame e_tran %.3g mm, e_rot %.3g deg; physical "
                "e_tran %.3g mm, e_rot %.3g deg\n", which, e_tran, e_rot, p_tran, p_rot);
    EXPECT_LT(e_tran, 1e-5) << which;
    EXPECT_LT(e_rot, 1e-6) << which;
    EXPECT_NEAR(p_rot, 0.8, 0.01) << which;  // 0.5 + 0.3 deg about z; 0.01: ZYZ split slack
    EXPECT_GT(p_tran, 2.0) << which;
  }
  // The link-1 offsets put in above, read back (1e-9: rounding of the mm / deg conversions).
  EXPECT_FALSE(r.frames.best_fit);
  EXPECT_NEAR(1e3 * r.frames.dd1_m[0], 3.0, 1e-9);
  EXPECT_NEAR(RadToDeg(r.frames.dtheta1_rad[1]), -0.3, 1e-9);
}

TEST_F(HandclaspRunTest, ConstrainedIsNotWorseThanGeneralOverASeededBatch) {
  // The paper's set-ups with nominal pendant models (geometry errors of a well-kept factory
  // arm, sigma 0.5 mm / 0.05 deg) and 0.5 mm operator error; 3 trials each (seeds 11..13). The claim of the paper
  // (Table 1, section 4) is checked on the batch means.
  for (const char* name : kSetups) {
    const std::string out = ::testing::TempDir() + "/hc_batch_" + name;
    const std::string scenario = out + ".yaml";
    {
      std::ifstream in(kDir + "gan2014_" + name + ".yaml");
      std::stringstream text;
      text << in.rdbuf();
      std::string s = text.str();
      const std::string from = "trials: 10", to = "trials: 3";
      ASSERT_NE(s.find(from), std::string::npos);
      s.replace(s.find(from), from.size(), to);
      // Model paths are relative to the scenario's folder: make them absolute.
      for (const std::string m : {"reinovo_r1.yaml", "reinovo_r2.yaml"}) {
        const std::string rel = "../models/" + m;
        s.replace(s.find(rel), rel.size(), std::string(TWIN_SOURCE_DIR) + "/models/" + m);
      }
      std::ofstream(scenario) << s;
    }
    std::ostringstream progress;
    const int rc = RunHandclaspScenario(scenario, out, progress);
    ASSERT_EQ(rc, 0) << name << "\n" << progress.str();
    std::ifstream f(out + "/report.json");
    const nlohmann::json rep = nlohmann::json::parse(f);
    const nlohmann::json& b = rep["base_frame"]["batch"];
    const double g_t = b["general"]["mean_e_tran_mm"], g_r = b["general"]["mean_e_rot_deg"];
    const double c_t = b["constrained"]["mean_e_tran_mm"], c_r = b["constrained"]["mean_e_rot_deg"];
    std::printf("[ measured ] %s over 3 trials: general e_tran %.2f mm, e_rot %.3f deg; "
                "constrained e_tran %.2f mm, e_rot %.3f deg\n", name, g_t, g_r, c_t, c_r);
    // On the means of 3 trials. The refinement fixes rotation angles, so e_rot may not grow
    // beyond 1% (the free angle stays the general one's, up to re-fitting). e_tran is re-fitted
    // by eq. 12 with the new rotation and can move either way: the paper's own Table 1 row 1
    // has the constrained e_tran 3.5% worse (5.9 vs 5.7 mm), hence a 5% allowance.
    // Floor-wall: the paper's H_tru stands 0.126 deg off a perfect wall (middle ZYZ angle
    // 89.874), and the refinement forces 90 deg (eq. 17-21), so the constrained middle angle is
    // off by exactly 0.126 deg whatever the data; where the general error is smaller, e_rot
    // grows up to that (the paper's own row 12: 0.126 vs 0.121 deg). Allowed on top.
    const double wall_tilt_deg = std::string(name) == "floor_wall" ? 90.0 - 89.874 : 0.0;
    EXPECT_LE(c_r, 1.01 * g_r + wall_tilt_deg) << name;
    EXPECT_LE(c_t, 1.05 * g_t) << name;
    EXPECT_EQ(rep["base_frame"]["installation"], std::string(name) == "floor_floor" ? "floor-floor"
                                                 : std::string(name) == "floor_wall" ? "floor-wall"
                                                                                      : "floor-ceiling");
    EXPECT_FALSE(std::filesystem::exists(out + "/report.json.tmp"));
  }
}

// `section` holds the keys after the told ones ("{pointz: auto}").
void ExpectSectionError(const std::string& section, const std::string& where_part,
                        const std::string& message_part) {
  Scenario sc = LoadScenario(kDir + "gan2014_floor_floor.yaml");
  const std::string text =
      section == "{}" ? ToldSection("floor_floor") + "}"
                      : ToldSection("floor_floor") + ", " + section.substr(1);
  sc.handclasp = YamlField{YAML::Load(text), "scenario.handclasp"};
  try {
    ParseHandclaspConfig(sc);
    ADD_FAILURE() << "no InputError for " << section;
  } catch (const InputError& e) {
    EXPECT_NE(e.where().find(where_part), std::string::npos) << e.what();
    EXPECT_NE(e.message().find(message_part), std::string::npos) << e.what();
  }
}

TEST_F(HandclaspRunTest, SectionErrorsNameTheKey) {
  ExpectSectionError("{pointz: auto}", "scenario.handclasp", "pointz");
  ExpectSectionError("{points: some}", "scenario.handclasp.points", "auto");
  ExpectSectionError("{points: [[0, 0, 500], [100, 0, 500]]}", "scenario.handclasp.points",
                     "at least 4");
  ExpectSectionError("{operator_error_mm: -1}", "scenario.handclasp.operator_error_mm", ">= 0");
  ExpectSectionError("{constraint: floor_roof}", "scenario.handclasp.constraint", "floor_wall");
  ExpectSectionError("{trials: 0}", "scenario.handclasp.trials", "1..1000");
  // Plausibility limits.
  ExpectSectionError("{operator_error_mm: 1e6}", "scenario.handclasp.operator_error_mm",
                     "at most 10 mm");
  ExpectSectionError("{points: [[0, 0, 500], [100, 0, 500], [0, 100, 500], [1e9, 0, 0]]}",
                     "scenario.handclasp.points[3]", "within 5000 mm");
  // The told values are required: the truth is never used in their place.
  Scenario sc = LoadScenario(kDir + "gan2014_floor_floor.yaml");
  sc.handclasp = YamlField{YAML::Load("{points: auto}"), "scenario.handclasp"};
  EXPECT_THROW(ParseHandclaspConfig(sc), InputError);
  sc.handclasp = YamlField{};
  EXPECT_THROW(ParseHandclaspConfig(sc), InputError);
}

TEST_F(HandclaspRunTest, SectionDefaultsFollowTheInstallations) {
  for (const char* name : kSetups) {
    Scenario sc = LoadScenario(kDir + "gan2014_" + name + ".yaml");
    sc.handclasp = YamlField{YAML::Load(ToldSection(name) + "}"), "scenario.handclasp"};
    const HandclaspConfig c = ParseHandclaspConfig(sc);
    EXPECT_TRUE(c.auto_points);
    EXPECT_EQ(c.trials, 1);
    EXPECT_EQ(c.operator_error_m, 0.0);
    EXPECT_EQ(std::string(ToString(c.constraint)),
              std::string(name) == "floor_floor"     ? "floor-floor"
              : std::string(name) == "floor_ceiling" ? "floor-ceiling"
                                                     : "floor-wall");
  }
}

}  // namespace
}  // namespace twin
