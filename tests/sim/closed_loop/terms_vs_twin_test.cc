// Each estimator-side error term (calib/model/terms/) against the twin effect it models
// (sim/effects/), written independently: with the term's parameters set to the effect's
// magnitude, the term predicts from the encoder readings where the twin's physics put the
// links and the target, to 1e-9 m. The twin settles far tighter than by default here
// (settle_speed 1e-10 rad/s), so that its own settling is not what the comparison measures.
#include <cmath>
#include <map>
#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/model/robot_model.h"
#include "calib/procedures/optical_axis_procedure.h"
#include "sim/cell/twin_cell.h"
#include "sim/world/mujoco_handles.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoPose;
using testing::DemoTwinSpec;

// 1e-9 m: the agreement; the tight settling leaves < 1e-11 rad of motion, and both
// sides compute the same physics in double (the sag's fixed point converges to ~1e-12 rad).
constexpr double kAgreement = 1e-9;
constexpr double kTwinGravity = 9.81;  // the MJCF's gravity (mjcf_writer.cc)

class TermsVsTwin : public ::testing::Test {
 protected:
  void SetUp() override { InstallMujocoErrorHandlers(); }
};

EffectSpec EffectOf(const std::string& type, std::map<std::string, double> params, int robot,
                    int joint) {
  EffectSpec e;
  e.type = type;
  e.params = std::move(params);
  e.robot = robot;
  e.joint = joint;
  e.where = "test effects";
  return e;
}

TwinSpec TightSpec() {
  TwinSpec spec = DemoTwinSpec();
  spec.physics.settle_speed = 1e-10;
  spec.physics.settle_steps = 50;
  spec.physics.max_steps = 200000;
  return spec;
}

// The spec with robot 0's tool link of zero length. The twin's thermal effects grow every
// link of its model, the tool link too; the estimator's thermal terms grow the joint links and
// not the tool link (what the flange carries is not the arm's structure: robot_model.h). The
// two are written independently and differ there on purpose; with no tool link length the
// comparison is of the arm alone.
TwinSpec WithoutToolLength(TwinSpec spec) {
  spec.robots[0].model.tool().dh.d = 0.0;
  spec.robots[0].model.tool().dh.a = 0.0;
  return spec;
}

// Robot 0's pose targets around the demo pose, loading its joints differently.
std::vector<JointVector> Targets() {
  std::vector<JointVector> out;
  const double moves[4][6] = {{0.2, -0.1, 0.15, 0.3, -0.2, 0.5},
                              {-0.3, 0.2, -0.25, -0.4, 0.3, -0.6},
                              {0.1, 0.35, 0.1, 0.8, -0.4, 1.0},
                              {-0.15, -0.25, 0.3, -0.7, 0.25, -1.2}};
  for (const auto& m : moves) {
    JointVector q = DemoPose();
    for (int i = 0; i < 6; ++i) q(i) += m[i];
    out.push_back(q);
  }
  return out;
}

// The tool-link frame L7 of robot `k` in the world, as the twin's physics placed it.
Vector3 TwinTool(const TwinCell& cell, int k) { return cell.SiteFrames(k)[7].translation(); }

// The estimator's prediction of the same point from the readings (robot base in the world
// from the spec: not part of what is compared).
Vector3 TermTool(const RobotModel& m, const MeasurementContext& c, const Transform& X_WB) {
  return X_WB * EndPose(m, c).translation();
}

// Link masses and centres of mass as the twin's MuJoCo model has them (each link body with
// the bodies welded to it: tools, camera, board, tip), in the true DH frames: the term is
// given the very masses the physics uses.
KinematicModel WithTwinMasses(KinematicModel chain, const TwinCell& cell, int k) {
  const MjModelPtr m = LoadMjcfFromString(cell.mjcf());
  MjDataPtr d(mj_makeData(m.get()));
  const TwinTruth t = cell.Truth();
  for (int r = 0; r < kMaxRobots; ++r) {
    for (int i = 0; i < 6; ++i) {
      const std::string name = "robot" + std::to_string(r + 1) + "_j" + std::to_string(i + 1);
      d->qpos[m->jnt_qposadr[mj_name2id(m.get(), mjOBJ_JOINT, name.c_str())]] = t.q_link[r](i);
    }
  }
  mj_forward(m.get(), d.get());
  const std::vector<Transform> sites = cell.SiteFrames(k);
  const std::string prefix = "robot" + std::to_string(k + 1) + "_link";
  std::vector<double> mass(7, 0.0);
  std::vector<Vector3> moment(7, Vector3::Zero());
  for (int b = 1; b < m->nbody; ++b) {
    int owner = b;  // climb to the link body that carries b
    int link = -1;
    while (owner > 0) {
      const char* n = mj_id2name(m.get(), mjOBJ_BODY, owner);
      const std::string name = n ? n : "";
      if (name.rfind(prefix, 0) == 0) {
        link = std::stoi(name.substr(prefix.size())) - 1;
        break;
      }
      owner = m->body_parentid[owner];
    }
    if (link < 0) continue;
    mass[link] += m->body_mass[b];
    moment[link] += m->body_mass[b] * Vector3(d->xipos + 3 * b);
  }
  for (int i = 0; i < 6; ++i) {
    chain.links[i].inertia.mass = mass[i];
    chain.links[i].inertia.p_LiCom = sites[i + 1].inverse() * (moment[i] / mass[i]);
  }
  chain.tool().inertia = LinkInertia{};
  return chain;
}

TEST_F(TermsVsTwin, JointComplianceTermPredictsTheTwinsGravitySag) {
  TwinSpec spec = TightSpec();
  spec.effects.push_back(EffectOf("joint_compliance", {{"stiffness_Nm_per_rad", 2e4}}, 0, 1));
  spec.effects.push_back(EffectOf("joint_compliance", {{"stiffness_Nm_per_rad", 3e4}}, 0, 2));
  TwinCell cell(spec);
  double largest_sag = 0.0;
  for (const JointVector& target : Targets()) {
    ASSERT_EQ(cell.MoveTo(0, target).status, MoveStatus::kSettled);
    const KinematicModel chain = WithTwinMasses(cell.Truth().models[0], cell, 0);
    RobotModel m = MakeRobotModel(chain);
    m.gravity = kTwinGravity;
    m = WithTerm(m, MakeErrorTerm({"joint_compliance", 1, {}}, chain, "r1"));
    m = WithTerm(m, MakeErrorTerm({"joint_compliance", 2, {}}, chain, "r1"));
    m.term_values << 1.0 / 2e4, 1.0 / 3e4;
    const MeasurementContext c = ContextOf(cell.ReadEncoders(0));
    const Vector3 twin = TwinTool(cell, 0);
    const Vector3 term = TermTool(m, c, spec.robots[0].X_WB);
    const Vector3 rigid = TermTool(MakeRobotModel(chain), c, spec.robots[0].X_WB);
    largest_sag = std::max(largest_sag, (twin - rigid).norm());
    EXPECT_LT((twin - term).norm(), kAgreement) << "sag " << (twin - rigid).norm() << " m";
  }
  EXPECT_GT(largest_sag, 1e-4) << "the poses must load the compliant joints";
}

TEST_F(TermsVsTwin, TransmissionErrorTermEqualsTheTwinsGearError) {
  TwinSpec spec = TightSpec();
  spec.effects.push_back(EffectOf(
      "transmission_error", {{"amplitude_deg", 0.05}, {"harmonic", 2}, {"phase_deg", 30}}, 0, 3));
  spec.effects.push_back(EffectOf("transmission_error", {{"amplitude_deg", 0.02}, {"harmonic", 1}}, 0, 1));
  TwinCell cell(spec);
  const KinematicModel chain = cell.Truth().models[0];
  RobotModel m = MakeRobotModel(chain);
  m = WithTerm(m, MakeErrorTerm({"transmission_error", 3, {2}}, chain, "r1"));
  m = WithTerm(m, MakeErrorTerm({"transmission_error", 1, {1}}, chain, "r1"));
  // A sin(h q + phi) = A cos(phi) sin(h q) + A sin(phi) cos(h q).
  const double a4 = DegToRad(0.05), phi = DegToRad(30.0), a2 = DegToRad(0.02);
  m.term_values << a4 * std::cos(phi), a4 * std::sin(phi), a2, 0.0;
  double largest = 0.0;  // how far the rigid chain misses
  for (const JointVector& target : Targets()) {
    ASSERT_EQ(cell.MoveTo(0, target).status, MoveStatus::kSettled);
    const MeasurementContext c = ContextOf(cell.ReadEncoders(0));
    EXPECT_LT((TwinTool(cell, 0) - TermTool(m, c, spec.robots[0].X_WB)).norm(), kAgreement);
    largest = std::max(
        largest, (TwinTool(cell, 0) - TermTool(MakeRobotModel(chain), c, spec.robots[0].X_WB)).norm());
    JointVector q(6);
    double s;
    const Eigen::VectorXd p = GetParameters(m);
    LinkAnglesT<double>(m, p.data(), c, q.data(), &s);
    // 1e-11 rad: the twin's link angle settles to < 1e-11 rad of its target here.
    EXPECT_LT((q - cell.Truth().q_link[0]).cwiseAbs().maxCoeff(), 1e-11);
  }
  EXPECT_GT(largest, 1e-4) << "the gear errors must be visible";
}

TEST_F(TermsVsTwin, BacklashTermTakesTheSideOfTheApproach) {
  TwinSpec spec = TightSpec();
  spec.effects.push_back(EffectOf("backlash", {{"width_deg", 0.1}}, 0, 0));
  spec.effects.push_back(EffectOf("backlash", {{"width_deg", 0.06}}, 0, 4));
  TwinCell cell(spec);
  const KinematicModel chain = cell.Truth().models[0];
  RobotModel m = MakeRobotModel(chain);
  m = WithTerm(m, MakeErrorTerm({"backlash", 0, {}}, chain, "r1"));
  m = WithTerm(m, MakeErrorTerm({"backlash", 4, {}}, chain, "r1"));
  m.term_values << -0.5 * DegToRad(0.1), -0.5 * DegToRad(0.06);  // the link lags the motor
  JointVector previous = cell.ReadEncoders(0);
  JointVector approach = JointVector::Zero(6);
  for (const JointVector& target : Targets()) {
    ASSERT_EQ(cell.MoveTo(0, target).status, MoveStatus::kSettled);
    for (int i = 0; i < 6; ++i) {
      if (target(i) != previous(i)) approach(i) = target(i) > previous(i) ? 1.0 : -1.0;
    }
    previous = target;
    MeasurementContext c = ContextOf(cell.ReadEncoders(0));
    c.approach = approach;
    EXPECT_LT((TwinTool(cell, 0) - TermTool(m, c, spec.robots[0].X_WB)).norm(), kAgreement);
    c.approach = -approach;  // the wrong side is off by the whole dead band
    EXPECT_GT((TwinTool(cell, 0) - TermTool(m, c, spec.robots[0].X_WB)).norm(), 1e-4);
  }
}

TEST_F(TermsVsTwin, ThermalGrowthTermScalesTheArmLikeTheTwin) {
  TwinSpec spec = WithoutToolLength(TightSpec());
  spec.effects.push_back(EffectOf("thermal_growth", {{"delta_T_K", 12.0}, {"coefficient_per_K",
                                                                          2.3e-5}}, 0, -1));
  TwinCell cell(spec);
  // The estimator's chain is the geometry before the growth (the twin's truth carries it).
  const KinematicModel chain = spec.robots[0].model;
  RobotModel m = WithTerm(MakeRobotModel(chain),
                          MakeErrorTerm({"thermal_growth", -1, {}}, chain, "r1"));
  m.term_values << 2.3e-5;
  for (const JointVector& target : Targets()) {
    ASSERT_EQ(cell.MoveTo(0, target).status, MoveStatus::kSettled);
    MeasurementContext c = ContextOf(cell.ReadEncoders(0));
    c.temperature_delta_K = 12.0;
    EXPECT_LT((TwinTool(cell, 0) - TermTool(m, c, spec.robots[0].X_WB)).norm(), kAgreement);
    // 12 K grow a ~1 m reach by ~0.3 mm: the cold chain misses by more than 0.1 mm.
    EXPECT_GT((TwinTool(cell, 0) - TermTool(MakeRobotModel(chain), c, spec.robots[0].X_WB)).norm(),
              1e-4);
  }
}

TEST_F(TermsVsTwin, ThermalDriftTermScalesTheArmLikeTheTwinsWarmUp) {
  // The arm warms by up to 20 K with a 60 s time constant (fast, so that a few moves see it):
  // scale(t) = 1 + 2.3e-5 * 20 * (1 - exp(-t / 60 s)), written here from the effect's
  // definition, not taken from the twin.
  constexpr double kGrowth = 2.3e-5 * 20.0, kTau = 60.0;
  TwinSpec spec = WithoutToolLength(TightSpec());
  spec.effects.push_back(EffectOf("thermal_drift", {{"delta_T_K", 20.0}, {"coefficient_per_K",
                                                                          2.3e-5},
                                                    {"time_constant_s", kTau}}, 0, -1));
  TwinCell cell(spec);
  const KinematicModel chain = spec.robots[0].model;
  double last_gap = 0.0, last_time = 0.0;
  for (const JointVector& target : Targets()) {
    ASSERT_EQ(cell.MoveTo(0, target).status, MoveStatus::kSettled);
    const TwinTruth truth = cell.Truth();
    ASSERT_GT(truth.time_s, last_time);  // the clock runs with the moves
    last_time = truth.time_s;
    const double scale = 1.0 + kGrowth * (1.0 - std::exp(-truth.time_s / kTau));
    EXPECT_NEAR(truth.length_scale[0], scale, 1e-15);
    EXPECT_EQ(truth.length_scale[1], 1.0);  // robot 1 does not drift
    // The estimator's term (d, a of every link times 1 + r t) at the rate that gives this
    // moment's scale predicts the twin's flange-and-tool point from the readings.
    RobotModel m = WithTerm(MakeRobotModel(chain),
                            MakeErrorTerm({"thermal_drift", -1, {}}, chain, "r1"));
    m.term_values << (scale - 1.0) / truth.time_s;
    MeasurementContext c = ContextOf(cell.ReadEncoders(0));
    c.time_s = truth.time_s;
    EXPECT_LT((TwinTool(cell, 0) - TermTool(m, c, spec.robots[0].X_WB)).norm(), kAgreement)
        << "t = " << truth.time_s << " s";
    // The warm-up term with the twin's time constant (1 min) and final growth predicts it at
    // every time; so does one started at 2 min whose log-ratio halves it.
    RobotModel warmup = WithTerm(MakeRobotModel(chain),
                                 MakeErrorTerm({"thermal_warmup", -1, {1}}, chain, "r1"));
    warmup.term_values << kGrowth, 0.0;
    EXPECT_LT((TwinTool(cell, 0) - TermTool(warmup, c, spec.robots[0].X_WB)).norm(), kAgreement)
        << "t = " << truth.time_s << " s";
    RobotModel slower = WithTerm(MakeRobotModel(chain),
                                 MakeErrorTerm({"thermal_warmup", -1, {2}}, chain, "r1"));
    slower.term_values << kGrowth, std::log(0.5);
    EXPECT_LT((TwinTool(cell, 0) - TermTool(slower, c, spec.robots[0].X_WB)).norm(), kAgreement)
        << "t = " << truth.time_s << " s";
    last_gap = (TwinTool(cell, 0) - TermTool(MakeRobotModel(chain), c, spec.robots[0].X_WB)).norm();
  }
  // After the moves (several seconds) the arm has grown measurably: tens of micrometres
  // over its ~1 m reach, far above the 1e-9 m agreement.
  EXPECT_GT(last_gap, 1e-5) << "t = " << last_time << " s";
}

// A temperature sensor on the drifting arm (noise-free here) reads the ambient plus the
// warming, and the estimator's thermal growth (d, a of every joint link times 1 + k dT) with the
// material's coefficient and the sensor's change since the first reading predicts the twin's
// flange-and-tool point at every time: the drift becomes a function of a measured quantity.
TEST_F(TermsVsTwin, ATemperatureSensorTurnsTheWarmUpIntoAThermalGrowth) {
  constexpr double kCoefficient = 2.3e-5, kDeltaT = 20.0, kTau = 60.0, kAmbient = 21.5;
  TwinSpec spec = WithoutToolLength(TightSpec());
  spec.effects.push_back(EffectOf("thermal_drift", {{"delta_T_K", kDeltaT},
                                                    {"coefficient_per_K", kCoefficient},
                                                    {"time_constant_s", kTau}}, 0, -1));
  spec.robots[0].temperature_sensor = {true, kAmbient, 0.0};
  TwinCell cell(spec);
  EXPECT_TRUE(std::isnan(cell.ReadTemperatureC(1)));  // robot 1 has no sensor
  const KinematicModel chain = spec.robots[0].model;
  const double first = cell.ReadTemperatureC(0);
  const double first_time = cell.Truth().time_s;
  for (const JointVector& target : Targets()) {
    ASSERT_EQ(cell.MoveTo(0, target).status, MoveStatus::kSettled);
    const TwinTruth truth = cell.Truth();
    const double reading = cell.ReadTemperatureC(0);
    // The sensor against the effect's definition, written here (1e-12 K: rounding).
    EXPECT_NEAR(reading, kAmbient + kDeltaT * (1.0 - std::exp(-truth.time_s / kTau)), 1e-12);
    // The model's reference is the first reading, whose growth the geometry carries: scale
    // the chain to that moment (the identification would absorb it in the lengths).
    KinematicModel at_first = chain;
    const double s0 = 1.0 + kCoefficient * kDeltaT * (1.0 - std::exp(-first_time / kTau));
    for (Link& l : at_first.links) {
      l.dh.d *= s0;
      l.dh.a *= s0;
    }
    RobotModel g = WithTerm(MakeRobotModel(at_first),
                            MakeErrorTerm({"thermal_growth", -1, {}}, at_first, "r1"));
    // s0 (1 + k' (T - T0)) with k' = k / s0 is 1 + k T: the twin's scale, exactly.
    g.term_values << kCoefficient / s0;
    MeasurementContext c = ContextOf(cell.ReadEncoders(0));
    c.temperature_delta_K = reading - first;
    EXPECT_LT((TwinTool(cell, 0) - TermTool(g, c, spec.robots[0].X_WB)).norm(), kAgreement)
        << "t = " << truth.time_s << " s";
  }
}

TEST_F(TermsVsTwin, MountDeflectionTermPredictsTheSpringMountedBoard) {
  TwinSpec spec = TightSpec();
  spec.effects.push_back(EffectOf("mount_deflection", {{"deflection_x_mm", 0.03},
                                                       {"deflection_y_mm", 0.04},
                                                       {"deflection_z_mm", 0.05}}, 1, -1));
  TwinCell cell(spec);
  // The board on robot 1 as its tool: the end frame is the board frame T (origin P).
  const KinematicModel chain = BoardRobotModel(cell.Truth().models[1], spec.board.X_FT);
  RobotModel m = WithTerm(MakeRobotModel(chain, spec.robots[1].X_WB.linear().transpose() *
                                                    -Vector3::UnitZ()),
                          MakeErrorTerm({"mount_deflection", -1, {}}, chain, "r2"));
  m.term_values << 3e-5, 4e-5, 5e-5;
  double largest = 0.0;
  for (const JointVector& t0 : Targets()) {
    ASSERT_EQ(cell.MoveTo(1, t0).status, MoveStatus::kSettled);
    const MeasurementContext c = ContextOf(cell.ReadEncoders(1));
    const Vector3 twin = cell.Truth().X_WT.translation();
    const Vector3 rigid = TermTool(MakeRobotModel(chain), c, spec.robots[1].X_WB);
    largest = std::max(largest, (twin - rigid).norm());
    EXPECT_LT((twin - TermTool(m, c, spec.robots[1].X_WB)).norm(), kAgreement);
  }
  EXPECT_GT(largest, 2e-5) << "the board must hang on its springs";
}

}  // namespace
}  // namespace twin
