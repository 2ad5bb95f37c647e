#include "sim/world/mjcf_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "calib/kinematics/forward_kinematics.h"
#include "sim/render/camera_image.h"
#include "sim/world/mujoco_handles.h"
#include "tests/sim/test_twin_specs.h"

namespace twin {
namespace {

using testing::DemoTwinSpec;

// MuJoCo warnings throw (DESIGN.md convention 10), so any warning fails the test.
class MjcfWriterTest : public ::testing::Test {
 protected:
  void SetUp() override { InstallMujocoErrorHandlers(); }
};

std::array<std::vector<JointDrive>, kMaxRobots> Drives(const TwinSpec& spec) {
  std::array<std::vector<JointDrive>, kMaxRobots> drives;
  for (int k = 0; k < kMaxRobots; ++k) {
    drives[k].assign(spec.robots[k].model.num_joints(), {spec.physics.stiffness, true});
  }
  return drives;
}

std::array<KinematicModel, kMaxRobots> Models(const TwinSpec& spec) {
  return {spec.robots[0].model, spec.robots[1].model};
}

// A compiled twin world.
struct World {
  explicit World(const TwinSpec& spec)
      : mjcf(WriteTwinMjcf(spec, Models(spec), Drives(spec))),
        m(LoadMjcfFromString(mjcf)),
        d(mj_makeData(m.get())) {}

  int Id(mjtObj type, const std::string& name) const {
    const int id = mj_name2id(m.get(), type, name.c_str());
    EXPECT_GE(id, 0) << "no MuJoCo object named " << name;
    return id;
  }
  // Sets robot `k`'s hinge angles (link side) to q.
  void SetJoints(int k, const JointVector& q) {
    for (int i = 0; i < 6; ++i) {
      const int j = Id(mjOBJ_JOINT, "robot" + std::to_string(k + 1) + "_j" + std::to_string(i + 1));
      d->qpos[m->jnt_qposadr[j]] = q(i);
    }
  }
  Transform SitePose(const std::string& name) const {
    const int s = Id(mjOBJ_SITE, name);
    return FromMj(d->site_xpos + 3 * s, d->site_xmat + 9 * s);
  }
  static Transform FromMj(const mjtNum* pos, const mjtNum* mat) {
    Transform X = Transform::Identity();
    X.translation() = Vector3(pos[0], pos[1], pos[2]);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) X.linear()(r, c) = mat[3 * r + c];
    }
    return X;
  }

  std::string mjcf;
  MjModelPtr m;
  MjDataPtr d;
};

// Angle of the rotation between two frames [rad].
double AngleBetween(const Transform& A, const Transform& B) {
  return Eigen::AngleAxisd(A.linear().transpose() * B.linear()).angle();
}

JointVector RandomJoints(const KinematicModel& m, std::mt19937_64& rng) {
  JointVector q(m.num_joints());
  for (int i = 0; i < m.num_joints(); ++i) {
    q(i) = std::uniform_real_distribution<double>(m.links[i].limits.lower,
                                                   m.links[i].limits.upper)(rng);
  }
  return q;
}

std::string Name(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "?";
}

TEST_F(MjcfWriterTest, SitesMatchCalibForwardKinematicsForEveryInstallation) {
  // The MJCF carries every number as its shortest round-trip decimal, so MuJoCo's body frames
  // are calib's to the last bit before composition; MuJoCo then composes six or seven
  // transforms in double (quaternion products, normalisation), and calib's own products round
  // the same way: both land within ~1e-15 m / rad of each other. 1e-9 m (1 nm) and 1e-9 rad
  // leave six orders of margin yet catch any formula error (the smallest geometric effect the
  // bench injects is ~1e-6 m, and the old 6-digit %g writing alone gave ~1e-7).
  constexpr double kTol = 1e-9;
  constexpr int kConfigs = 25;
  std::mt19937_64 rng(7);
  double max_pos = 0, max_rot = 0;
  for (Installation inst : {Installation::kFloor, Installation::kCeiling, Installation::kWall}) {
    TwinSpec spec = DemoTwinSpec(inst);
    // Non-trivial base and end transforms, and Hayati betas, as perturbed true models have.
    spec.robots[0].model.X_BL0 = testing::Pose(Vector3(0.01, -0.02, 0.03), Vector3(1, 1, 0), 0.02);
    spec.robots[1].model.links[1].dh.beta = 0.003;
    spec.robots[1].model.links[6].dh.beta = -0.01;
    World w(spec);
    for (int c = 0; c < kConfigs; ++c) {
      std::array<JointVector, kMaxRobots> q;
      for (int k = 0; k < kMaxRobots; ++k) {
        q[k] = RandomJoints(spec.robots[k].model, rng);
        w.SetJoints(k, q[k]);
      }
      mj_kinematics(w.m.get(), w.d.get());
      mj_camlight(w.m.get(), w.d.get());  // camera poses
      for (int k = 0; k < kMaxRobots; ++k) {
        const FrameSet f = ForwardKinematics(spec.robots[k].model, q[k]);
        const Transform& X_WB = spec.robots[k].X_WB;
        for (int i = 0; i <= 7; ++i) {
          const std::string site = "robot" + std::to_string(k + 1) + "_L" + std::to_string(i);
          const Transform expected = X_WB * f.X_BL[i];
          const Transform got = w.SitePose(site);
          const double dp = (got.translation() - expected.translation()).norm();
          const double dr = AngleBetween(got, expected);
          max_pos = std::max(max_pos, dp);
          max_rot = std::max(max_rot, dr);
          ASSERT_LT(dp, kTol) << ToString(inst) << " " << site << " config " << c;
          ASSERT_LT(dr, kTol) << ToString(inst) << " " << site << " config " << c;
        }
        // Tip, camera and board hang off the flange F = L6.
        const Transform X_WF = X_WB * f.flange();
        const Transform tip = w.SitePose("robot" + std::to_string(k + 1) + "_tip");
        EXPECT_LT((tip.translation() - X_WF * spec.tips[k].X_FTip.translation()).norm(), kTol);
        if (k == spec.camera.robot) {
          const int cam = w.Id(mjOBJ_CAMERA, kHandCameraName);
          // MuJoCo's camera frame looks along -z, y up: turned by pi about x it is frame C.
          const Transform X_WC = World::FromMj(w.d->cam_xpos + 3 * cam, w.d->cam_xmat + 9 * cam) *
                                 Transform(Eigen::AngleAxisd(kPi, Vector3::UnitX()));
          const Transform expected = X_WF * spec.camera.X_FC;
          EXPECT_LT((X_WC.translation() - expected.translation()).norm(), kTol);
          EXPECT_LT(AngleBetween(X_WC, expected), kTol);
        }
        if (k == spec.board.robot) {
          const int b = w.Id(mjOBJ_BODY, "robot" + std::to_string(k + 1) + "_board");
          const Transform X_WT = World::FromMj(w.d->xpos + 3 * b, w.d->xmat + 9 * b);
          const Transform expected = X_WF * spec.board.X_FT;
          EXPECT_LT((X_WT.translation() - expected.translation()).norm(), kTol);
          EXPECT_LT(AngleBetween(X_WT, expected), kTol);
        }
      }
    }
  }
  std::printf("[ measured ] max FK difference MuJoCo vs calib: %.3g m, %.3g rad "
              "(3 installations x 2 robots x %d configurations x 8 frames)\n",
              max_pos, max_rot, kConfigs);
}

TEST_F(MjcfWriterTest, InertialsAreTheModelsExpressedInTheBodyFrames) {
  const TwinSpec spec = DemoTwinSpec();
  World w(spec);
  const JointVector q = spec.robots[0].q_initial;
  w.SetJoints(0, q);
  w.SetJoints(1, q);
  mj_forward(w.m.get(), w.d.get());
  for (int k = 0; k < kMaxRobots; ++k) {
    const KinematicModel& model = spec.robots[k].model;
    const FrameSet f = ForwardKinematics(model, q);
    for (int i = 0; i < 6; ++i) {
      const LinkInertia& in = model.links[i].inertia;
      const int b = w.Id(mjOBJ_BODY, "robot" + std::to_string(k + 1) + "_link" + std::to_string(i + 1));
      EXPECT_DOUBLE_EQ(w.m->body_mass[b], in.mass);
      const Transform X_WL = spec.robots[k].X_WB * f.X_BL[i + 1];
      const Vector3 com(w.d->xipos + 3 * b);
      EXPECT_LT((com - X_WL * in.p_LiCom).norm(), 1e-12) << "body " << b;
      // Inertia about the COM in world axes: R_WI diag(I) R_WI^T against R_WL I R_WL^T. MuJoCo
      // diagonalises in double: 1e-12 kg m^2 is far below the smallest moment (3e-4).
      const Transform X_WI = World::FromMj(w.d->xipos + 3 * b, w.d->ximat + 9 * b);
      const Vector3 diag(w.m->body_inertia + 3 * b);
      const Matrix3 got = X_WI.linear() * diag.asDiagonal() * X_WI.linear().transpose();
      const Matrix3 expected = X_WL.linear() * in.I_Com * X_WL.linear().transpose();
      EXPECT_LT((got - expected).norm(), 1e-12) << "body " << b;
    }
  }
  const int cam = w.Id(mjOBJ_BODY, "robot1_camera");
  EXPECT_DOUBLE_EQ(w.m->body_mass[cam], 0.3);
  const int board = w.Id(mjOBJ_BODY, "robot2_board");
  EXPECT_NEAR(w.m->body_mass[board], spec.board.mass_kg, 1e-12);
}

TEST_F(MjcfWriterTest, DrivesJointsAndOptionsFollowTheSpec) {
  TwinSpec spec = DemoTwinSpec();
  spec.physics.timestep_s = 0.001;
  spec.camera.msaa_samples = 2;
  std::array<std::vector<JointDrive>, kMaxRobots> drives = Drives(spec);
  drives[1][2].stiffness = 2e4;
  World w(spec);  // default drives, for the damping check below
  const MjModelPtr m = LoadMjcfFromString(WriteTwinMjcf(spec, Models(spec), drives));
  EXPECT_EQ(m->opt.timestep, 0.001);
  EXPECT_EQ(m->opt.integrator, mjINT_EULER);
  EXPECT_EQ(m->opt.gravity[2], -9.81);
  EXPECT_EQ(m->vis.quality.offsamples, 2);
  EXPECT_GE(m->vis.global.offwidth, 1600);
  EXPECT_GE(m->vis.global.offheight, 1200);
  ASSERT_EQ(m->nu, 2 * 6);
  for (int k = 0; k < kMaxRobots; ++k) {
    for (int i = 0; i < 6; ++i) {
      const std::string s = "robot" + std::to_string(k + 1) + "_";
      const int a = mj_name2id(m.get(), mjOBJ_ACTUATOR, (s + "a" + std::to_string(i + 1)).c_str());
      const int j = mj_name2id(m.get(), mjOBJ_JOINT, (s + "j" + std::to_string(i + 1)).c_str());
      ASSERT_GE(a, 0);
      ASSERT_GE(j, 0);
      EXPECT_EQ(m->actuator_trnid[2 * a], j);
      EXPECT_EQ(m->actuator_gainprm[a * mjNGAIN], drives[k][i].stiffness);
      EXPECT_EQ(m->actuator_biasprm[a * mjNBIAS + 1], -drives[k][i].stiffness);
      EXPECT_EQ(m->actuator_ctrllimited[a], 0);
      EXPECT_EQ(m->jnt_limited[j], 1);
      const JointLimits& lim = spec.robots[k].model.links[i].limits;
      EXPECT_EQ(m->jnt_range[2 * j], lim.lower);
      EXPECT_EQ(m->jnt_range[2 * j + 1], lim.upper);
      EXPECT_EQ(m->dof_armature[m->jnt_dofadr[j]], spec.physics.armature);
    }
  }
  // Damping ratio c / (2 sqrt(kp M_ii)) against MuJoCo's own joint-space inertia at the
  // initial pose: the writer's estimate models camera and board as point masses, so the ratio
  // is 1 within a few per cent there (and within about x/1.7 across the workspace).
  w.SetJoints(0, spec.robots[0].q_initial);
  w.SetJoints(1, spec.robots[1].q_initial);
  mj_forward(w.m.get(), w.d.get());
  std::vector<mjtNum> M(static_cast<size_t>(w.m->nv) * w.m->nv);
  mj_fullM(w.m.get(), M.data(), w.d->qM);
  std::printf("[ measured ] damping ratio at the initial pose:");
  for (int dof = 0; dof < w.m->nv; ++dof) {
    const double kp = spec.physics.stiffness;
    const double zeta = w.m->dof_damping[dof] / (2 * std::sqrt(kp * M[dof * w.m->nv + dof]));
    std::printf(" %.3f", zeta);
    EXPECT_NEAR(zeta, 1.0, 0.05) << "dof " << dof;
  }
  std::printf("\n");
}

TEST_F(MjcfWriterTest, HandCameraFovyFollowsTheCanvas) {
  TwinSpec spec = DemoTwinSpec();
  spec.camera.distortion.k1 = -0.2;
  spec.camera.distortion.k2 = 0.05;
  const World w(spec);
  const Intrinsics canvas =
      DistortionMapper(spec.camera.intrinsics, spec.camera.distortion).canvas();
  EXPECT_GT(canvas.height, spec.camera.intrinsics.height);
  const int cam = w.Id(mjOBJ_CAMERA, kHandCameraName);
  const double fovy = 2.0 * RadToDeg(std::atan(0.5 * canvas.height / canvas.fy));
  EXPECT_NEAR(w.m->cam_fovy[cam], fovy, 1e-12);
  EXPECT_GE(w.m->vis.global.offwidth, std::max(canvas.width, 1600));
  EXPECT_GE(w.m->vis.global.offheight, std::max(canvas.height, 1200));
  // <map znear> is stored as a float: 1e-9 m covers its rounding.
  EXPECT_NEAR(w.m->vis.map.znear * w.m->stat.extent, spec.camera.near_m, 1e-9);
}

TEST_F(MjcfWriterTest, CellAtRestHasNoContactsAndWristNeighboursAreExcluded) {
  const TwinSpec spec = DemoTwinSpec();
  World w(spec);
  w.SetJoints(0, spec.robots[0].q_initial);
  w.SetJoints(1, spec.robots[1].q_initial);
  mj_forward(w.m.get(), w.d.get());
  EXPECT_EQ(w.d->ncon, 0);
  EXPECT_EQ(WarningCount(w.d.get()), 0);
  // Links 4 and 6 both reach the wrist centre (link 5 has zero length) and link 1 stands on
  // the static base (MuJoCo's parent filter skips static bodies): excluded, nothing else is
  // (every other middle link is longer than the two radii).
  EXPECT_EQ(w.m->nexclude, 4);
  for (const char* k : {"robot1_", "robot2_"}) {
    const std::string s(k);
    EXPECT_NE(w.mjcf.find("<exclude body1=\"" + s + "link4\" body2=\"" + s + "link6\"/>"),
              std::string::npos);
    EXPECT_NE(w.mjcf.find("<exclude body1=\"" + s + "base\" body2=\"" + s + "link1\"/>"),
              std::string::npos);
  }
  // q = 0 (arm up, forearm level, flange down) is contact-free as well.
  w.SetJoints(0, JointVector::Zero(6));
  w.SetJoints(1, JointVector::Zero(6));
  mj_forward(w.m.get(), w.d.get());
  EXPECT_EQ(w.d->ncon, 0);
}

// The body pair of every contact, as names.
std::vector<std::pair<std::string, std::string>> ContactBodies(const World& w) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (int c = 0; c < w.d->ncon; ++c) {
    const int b1 = w.m->geom_bodyid[w.d->contact[c].geom1];
    const int b2 = w.m->geom_bodyid[w.d->contact[c].geom2];
    pairs.emplace_back(Name(w.m.get(), mjOBJ_BODY, b1), Name(w.m.get(), mjOBJ_BODY, b2));
  }
  return pairs;
}

bool HasPair(const std::vector<std::pair<std::string, std::string>>& pairs, const std::string& a,
             const std::string& b) {
  return std::any_of(pairs.begin(), pairs.end(), [&](const auto& p) {
    return (p.first == a && p.second == b) || (p.first == b && p.second == a);
  });
}

TEST_F(MjcfWriterTest, RobotRobotToolAndSelfContactsAreDetected) {
  const TwinSpec spec = DemoTwinSpec();
  World w(spec);
  // Robot 0 leans forward, forearm level: its camera runs into robot 1's board.
  JointVector reach = spec.robots[0].q_initial;
  reach(1) = -1.0;
  reach(2) = 1.0;
  w.SetJoints(0, reach);
  w.SetJoints(1, spec.robots[1].q_initial);
  mj_forward(w.m.get(), w.d.get());
  const auto robot_robot = ContactBodies(w);
  ASSERT_GT(w.d->ncon, 0);
  EXPECT_TRUE(HasPair(robot_robot, "robot1_camera", "robot2_board"));
  // Elbow folded onto the upper arm: links 2 and 4 of the same robot.
  JointVector folded = spec.robots[0].q_initial;
  folded(2) = DegToRad(-139);
  w.SetJoints(0, folded);
  w.SetJoints(1, JointVector::Zero(6));
  mj_forward(w.m.get(), w.d.get());
  EXPECT_TRUE(HasPair(ContactBodies(w), "robot1_link2", "robot1_link4")) << w.d->ncon << " contacts";
  // Wrist folded back: the camera (its own body, so the link 4 / link 6 exclusion does not
  // cover it) hits the forearm.
  JointVector wrist = spec.robots[0].q_initial;
  wrist(4) = -kPi / 2;
  w.SetJoints(0, wrist);
  mj_forward(w.m.get(), w.d.get());
  EXPECT_TRUE(HasPair(ContactBodies(w), "robot1_link4", "robot1_camera")) << w.d->ncon << " contacts";
}

// A one-robot cell's world holds that robot and nothing of a second robot, the camera or the
// board; it compiles and rests without contacts, and its sites are calib's frames.
TEST_F(MjcfWriterTest, AOneRobotCellHasOneRobotAndNoCameraOrBoard) {
  const TwinSpec spec = testing::OneRobotTwinSpec();
  const World w(spec);
  EXPECT_EQ(w.mjcf.find("robot2_"), std::string::npos);
  EXPECT_EQ(w.mjcf.find("<camera"), std::string::npos);
  EXPECT_EQ(w.mjcf.find("board"), std::string::npos);
  EXPECT_EQ(w.m->ncam, 0);
  EXPECT_EQ(mj_name2id(w.m.get(), mjOBJ_BODY, "robot1_camera"), -1);
  EXPECT_EQ(mj_name2id(w.m.get(), mjOBJ_BODY, "robot1_board"), -1);
  EXPECT_EQ(w.m->nu, spec.robots[0].model.num_joints());  // one actuator per joint of robot 1
  EXPECT_EQ(w.m->njnt, spec.robots[0].model.num_joints());
  EXPECT_GE(w.Id(mjOBJ_BODY, "robot1_tip"), 0);
  // The two-robot cell has both (so the checks above can fail).
  const World both(DemoTwinSpec());
  EXPECT_NE(both.mjcf.find("robot2_"), std::string::npos);
  EXPECT_EQ(both.m->ncam, 1);
  EXPECT_GE(both.Id(mjOBJ_BODY, "robot2_board"), 0);

  World rest(spec);
  rest.SetJoints(0, spec.robots[0].q_initial);
  mj_forward(rest.m.get(), rest.d.get());
  EXPECT_EQ(rest.d->ncon, 0);
  const FrameSet f = ForwardKinematics(spec.robots[0].model, spec.robots[0].q_initial);
  // The flange site against calib's FK (base at the origin), to the 1 nm of the
  // every-installation test above (double rounding of six composed transforms, ~1e-15 m).
  const Transform X_WF = rest.SitePose("robot1_L6");
  EXPECT_LT((X_WF.translation() - f.flange().translation()).norm(), 1e-9);
}

TEST_F(MjcfWriterTest, TipsCollideWithTheOtherRobotButNotWithEachOther) {
  const World w(DemoTwinSpec());
  const mjModel* m = w.m.get();
  const auto collide = [m](int g1, int g2) {
    return (m->geom_contype[g1] & m->geom_conaffinity[g2]) ||
           (m->geom_contype[g2] & m->geom_conaffinity[g1]);
  };
  const int tip0 = w.Id(mjOBJ_GEOM, "robot1_tip"), tip1 = w.Id(mjOBJ_GEOM, "robot2_tip");
  EXPECT_FALSE(collide(tip0, tip1));
  EXPECT_TRUE(collide(tip0, w.Id(mjOBJ_GEOM, "robot2_link6_d")));
  EXPECT_TRUE(collide(tip1, w.Id(mjOBJ_GEOM, "robot1_camera_housing")));
  EXPECT_FALSE(collide(tip0, w.Id(mjOBJ_GEOM, "robot1_link4_d")));
  EXPECT_TRUE(collide(w.Id(mjOBJ_GEOM, "robot1_link3_a"), w.Id(mjOBJ_GEOM, "robot2_board_plate")));
  EXPECT_FALSE(collide(w.Id(mjOBJ_GEOM, "floor"), w.Id(mjOBJ_GEOM, "robot1_link3_a")));
}

}  // namespace
}  // namespace twin
