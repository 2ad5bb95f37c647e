// Twin specs for sim/ tests, built in code (sim tests load no files). The arm numbers are those
// of models/reinovo_r1.yaml and models/reinovo_r2.yaml (kinematics, limits, masses, inertias).
#pragma once

#include <string>

#include "calib/kinematic_model.h"
#include "sim/twin_spec.h"

namespace twin::testing {

/// Reinovo-like arm `robot` (0: r1, 1: r2; they differ only in d6 and link 6's mass data).
inline KinematicModel ReinovoArm(int robot) {
  KinematicModel m;
  m.name = robot == 0 ? "r1" : "r2";
  struct Row {
    double th, d, a, al, lo, hi, mass, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz;
  };
  const double d6 = robot == 0 ? 0.1215 : 0.131;
  const double c6 = robot == 0 ? -0.0607 : -0.0655;
  const double i6 = robot == 0 ? 0.00065 : 0.00073;
  const Row rows[kNumLinks] = {
      {0, 0.1365, 0.100, 90, -170, 170, 7.0, -0.05, -0.0683, 0, 0.02598, 0.02432, 0.0279,
       -0.00262, 0, 0},
      {90, 0, 0.290, 0, -120, 120, 7.5, -0.145, 0, 0, 0.01838, 0.06175, 0.06175, 0, 0, 0},
      {0, 0, 0.121, 90, -140, 140, 4.5, -0.0605, 0, 0, 0.0081, 0.00954, 0.00954, 0, 0, 0},
      {0, 0.310, 0, -90, -180, 180, 2.5, 0, 0.155, 0, 0.02158, 0.00313, 0.02158, 0, 0, 0},
      {-90, 0, 0, 90, -120, 120, 1.5, 0, 0, 0, 0.00177, 0.00177, 0.00152, 0, 0, 0},
      {0, d6, 0, 0, -270, 270, 0.4, 0, 0, c6, i6, i6, 0.00032, 0, 0, 0},
      {-90, 0, 0.060, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}};
  for (int i = 0; i < kNumLinks; ++i) {
    const Row& r = rows[i];
    Link& l = m.links[i];
    l.name = i < kNumJoints ? "link" + std::to_string(i + 1) : "tool";
    l.dh = {DegToRad(r.th), r.d, r.a, DegToRad(r.al), 0.0};
    if (i < kNumJoints) l.limits = {DegToRad(r.lo), DegToRad(r.hi)};
    l.inertia.mass = r.mass;
    l.inertia.p_LiCom = Vector3(r.cx, r.cy, r.cz);
    l.inertia.I_Com << r.ixx, r.ixy, r.ixz, r.ixy, r.iyy, r.iyz, r.ixz, r.iyz, r.izz;
  }
  return m;
}

/// The demo pose of both arms (motor angles): upper arm leant back 0.6 rad, forearm level,
/// wrist straight, so the two flanges face each other across the cell and the hand camera on
/// robot 0 looks at the board on robot 1 from about 0.4 m (checked with calib's FK in tests);
/// joint 6 at 90 deg puts the world's down at the image's bottom.
inline JointVector DemoPose() {
  JointVector q;
  q << 0.0, 0.6, -0.6, 0.0, kPi / 2, kPi / 2;
  return q;
}

/// A transform from a translation and an axis-angle rotation.
inline Transform Pose(const Vector3& p, const Vector3& axis = Vector3::UnitZ(), double angle = 0) {
  Transform X = Transform::Identity();
  X.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  X.translation() = p;
  return X;
}

/// Two Reinovo-like arms with bases 1.2 m apart facing each other: robot 0 on the floor at the
/// origin facing +x; robot 1 at x = 1.2 m installed as `installation` (floor: turned 180 deg
/// about z; ceiling: turned 180 deg about x as well and raised to 1.6 m; wall: base z along
/// -x at 0.8 m height). Camera on robot 0, 4x4 board on robot 1, both in the demo pose (the
/// demo pose suits the floor installation; other installations keep it, for FK tests).
inline TwinSpec DemoTwinSpec(Installation installation = Installation::kFloor) {
  TwinSpec spec;
  for (int k = 0; k < kNumRobots; ++k) {
    spec.robots[k].model = ReinovoArm(k);
    spec.robots[k].q_initial = DemoPose();
  }
  spec.robots[0].X_WB = Transform::Identity();
  spec.robots[1].installation = installation;
  switch (installation) {
    case Installation::kFloor:
      spec.robots[1].X_WB = Pose(Vector3(1.2, 0, 0), Vector3::UnitZ(), kPi);
      break;
    case Installation::kCeiling:
      spec.robots[1].X_WB = Pose(Vector3(1.2, 0, 1.6), Vector3::UnitY(), kPi);  // Rz(pi) Rx(pi)
      break;
    case Installation::kWall:
      spec.robots[1].X_WB = Pose(Vector3(1.2, 0, 0.8), Vector3::UnitY(), -kPi / 2);
      break;
  }
  spec.camera.robot = 0;
  // Hand-eye: 5 cm in front of the flange, turned slightly so it is not trivial.
  spec.camera.X_FC = Pose(Vector3(0.004, -0.003, 0.05), Vector3(1, 2, 0), DegToRad(2.0));
  spec.board.robot = 1;
  spec.board.X_FT = Pose(Vector3(0.002, 0.001, 0.012), Vector3::UnitZ(), DegToRad(10.0));
  for (TipSpec& tip : spec.tips) tip.X_FTip = Pose(Vector3(0.0, 0.07, 0.0));
  return spec;
}

}  // namespace twin::testing
