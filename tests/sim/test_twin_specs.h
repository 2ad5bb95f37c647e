// Twin specs for sim/ tests, built in code (sim tests load no files). The arm numbers are those
// of models/reinovo_r1.yaml and models/reinovo_r2.yaml (kinematics, limits, masses, inertias).
#pragma once

#include <string>

#include "calib/kinematics/kinematic_model.h"
#include "sim/world/twin_spec.h"
#include "tests/calib/test_models.h"

namespace twin::testing {

/// Reinovo-like arm `robot` (0: r1, 1: r2), with its mass data.
inline KinematicModel ReinovoArm(int robot) { return ReinovoLikeModel(robot); }

/// The demo pose of both arms (motor angles): upper arm leant back 0.6 rad, forearm level,
/// wrist straight, so the two flanges face each other across the cell and the hand camera on
/// robot 0 looks at the board on robot 1 from about 0.4 m (checked with calib's FK in tests);
/// joint 6 at 90 deg puts the world's down at the image's bottom.
inline JointVector DemoPose() {
  JointVector q(6);
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
  for (int k = 0; k < kMaxRobots; ++k) {
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

/// A one-robot cell (a laser-tracker cell): DemoTwinSpec's robot 0 alone, in its demo pose,
/// with a laser tracker 2.5 m in front of it (beyond where robot 1 stood) and a reflector on
/// its flange; no camera, board or second robot (camera and board keep DemoTwinSpec's values,
/// which a one-robot cell ignores).
inline TwinSpec OneRobotTwinSpec() {
  TwinSpec spec = DemoTwinSpec();
  spec.num_robots = 1;
  spec.tracker.present = true;
  spec.tracker.robot = 0;
  spec.tracker.X_WT = Pose(Vector3(2.5, 0.3, 0.6), Vector3::UnitZ(), DegToRad(172.0));
  spec.tracker.p_FR = Vector3(0.04, -0.03, 0.08);
  return spec;
}

/// A 14 x 10 chessboard of 20 mm squares (0.6 kg) for `board`'s bracket: the intrinsics
/// target of the paper scenario, mounted as the board is.
inline BoardSpec IntrinsicsTarget(const BoardSpec& board) {
  BoardSpec target = board;
  target.squares_x = 14;
  target.squares_y = 10;
  target.square_m = 0.02;
  target.mass_kg = 0.6;
  return target;
}

}  // namespace twin::testing
