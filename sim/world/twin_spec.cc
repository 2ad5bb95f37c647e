#include "sim/world/twin_spec.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "calib/common/errors.h"
#include "calib/common/text_format.h"

namespace twin {
namespace {

// Largest angle between a base z axis and the direction its installation implies [deg].
constexpr double kInstallationToleranceDeg = 5.0;

// Every message starts with the TwinSpec field path ("board.square_m", "robots[1].q_initial[2]")
// followed by a space or ':'; bench/io/scenario.cc relies on this to point at the file line.
class Checker {
 public:
  explicit Checker(const std::string& where) : where_(where) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& message) const {
    throw InputError(where_, field + " " + message);
  }

  void Finite(double v, const std::string& field) const {
    if (!std::isfinite(v)) Fail(field, "must be a finite number, got " + Num(v));
  }
  void Positive(double v, const std::string& field, const std::string& unit) const {
    if (!(std::isfinite(v) && v > 0.0)) {
      Fail(field, "must be a finite number > 0" + unit + ", got " + Num(v));
    }
  }
  void NonNegative(double v, const std::string& field, const std::string& unit) const {
    if (!(std::isfinite(v) && v >= 0.0)) {
      Fail(field, "must be a finite number >= 0" + unit + ", got " + Num(v));
    }
  }
  void IntRange(int v, const std::string& field, int lo, int hi) const {
    if (v < lo || v > hi) {
      Fail(field, "must be from " + std::to_string(lo) + " to " + std::to_string(hi) +
                      ", got " + std::to_string(v));
    }
  }
  void IntAtLeast(int v, const std::string& field, int lo) const {
    if (v < lo) Fail(field, "must be >= " + std::to_string(lo) + ", got " + std::to_string(v));
  }
  void Rigid(const Transform& X, const std::string& field) const {
    const Matrix3 R = X.linear();
    if (!X.matrix().allFinite()) Fail(field, "must be a finite transform, got non-finite entries");
    const double orth = (R.transpose() * R - Matrix3::Identity()).norm();
    const double det = R.determinant();
    if (orth > 1e-9 || det < 0.0) {
      Fail(field, "must be a rigid transform (orthonormal rotation, det +1), got |R^T R - I| = " +
                      Num(orth) + ", det R = " + Num(det));
    }
    const Eigen::Matrix<double, 1, 4> bottom = X.matrix().row(3);
    if (bottom != Eigen::Matrix<double, 1, 4>(0, 0, 0, 1)) {
      Fail(field, "must be a rigid transform (last row 0 0 0 1)");
    }
  }

  static std::string Num(double v) { return ShortestNumber(v); }

 private:
  std::string where_;
};

// Angles for messages: 6 significant digits of degrees.
std::string Deg(double rad) {
  std::ostringstream os;
  os << std::setprecision(6) << RadToDeg(rad);
  return os.str();
}

std::string RobotField(int i, const std::string& member) {
  return "robots[" + std::to_string(i) + "]." + member;
}

void CheckInstallation(const Checker& c, const RobotSpec& robot, int i) {
  const Vector3 z_W = robot.X_WB.linear().col(2);
  // Elevation of the base z axis above the world's horizontal plane [deg].
  const double elevation = RadToDeg(std::asin(std::max(-1.0, std::min(1.0, z_W.z()))));
  const double tol = kInstallationToleranceDeg;
  bool ok = false;
  std::string expected;
  switch (robot.installation) {
    case Installation::kFloor:
      ok = elevation >= 90.0 - tol;
      expected = "within 5 deg of +z (world up)";
      break;
    case Installation::kCeiling:
      ok = elevation <= -90.0 + tol;
      expected = "within 5 deg of -z (world down)";
      break;
    case Installation::kWall:
      ok = std::abs(elevation) <= tol;
      expected = "within 5 deg of horizontal";
      break;
  }
  if (ok) return;
  std::ostringstream os;
  os << std::setprecision(4) << "is " << ToString(robot.installation)
     << ", but the base z axis in the world is (" << z_W.x() << ", " << z_W.y() << ", "
     << z_W.z() << "), " << elevation << " deg above horizontal; expected " << expected
     << " (robots[" << i << "].X_WB and the installation disagree)";
  c.Fail(RobotField(i, "installation"), os.str());
}

void CheckRobot(const Checker& c, const RobotSpec& robot, int i, const std::string& where) {
  try {
    ValidateModel(robot.model, where);
  } catch (const InputError& e) {
    c.Fail(RobotField(i, "model"), "(" + robot.model.name + "): " + e.message());
  }
  c.Rigid(robot.X_WB, RobotField(i, "X_WB"));
  if (robot.q_initial.size() != robot.model.num_joints()) {
    c.Fail(RobotField(i, "q_initial"), "must hold " + std::to_string(robot.model.num_joints()) +
                                           " joint angles (one per joint of " +
                                           robot.model.name + "), got " +
                                           std::to_string(robot.q_initial.size()));
  }
  for (int j = 0; j < robot.model.num_joints(); ++j) {
    const std::string field = RobotField(i, "q_initial[" + std::to_string(j) + "]");
    const double q = robot.q_initial(j);
    c.Finite(q, field);
    const JointLimits& lim = robot.model.links[j].limits;
    if (q < lim.lower || q > lim.upper) {
      c.Fail(field, "must be within joint " + std::to_string(j + 1) + "'s limits [" +
                        Deg(lim.lower) + ", " + Deg(lim.upper) + "] deg, got " + Deg(q) +
                        " deg (" + Checker::Num(q) + " rad)");
    }
  }
  CheckInstallation(c, robot, i);
}

void CheckCamera(const Checker& c, const CameraSpec& cam) {
  c.IntRange(cam.robot, "camera.robot", 0, kNumRobots - 1);
  c.Rigid(cam.X_FC, "camera.X_FC");
  const Intrinsics& in = cam.intrinsics;
  c.IntRange(in.width, "camera.intrinsics.width", 1, 4096);
  c.IntRange(in.height, "camera.intrinsics.height", 1, 4096);
  c.Positive(in.fx, "camera.intrinsics.fx", " px");
  c.Positive(in.fy, "camera.intrinsics.fy", " px");
  // Pixel centres sit at integer coordinates, so the image spans [-0.5, size - 0.5].
  const auto inside = [&](double v, int size, const std::string& field) {
    c.Finite(v, field);
    if (v < -0.5 || v > size - 0.5) {
      c.Fail(field, "must lie inside the image, [-0.5, " + Checker::Num(size - 0.5) +
                        "] px, got " + Checker::Num(v));
    }
  };
  inside(in.cx, in.width, "camera.intrinsics.cx");
  inside(in.cy, in.height, "camera.intrinsics.cy");
  const Distortion& d = cam.distortion;
  c.Finite(d.k1, "camera.distortion.k1");
  c.Finite(d.k2, "camera.distortion.k2");
  c.Finite(d.p1, "camera.distortion.p1");
  c.Finite(d.p2, "camera.distortion.p2");
  c.Finite(d.k3, "camera.distortion.k3");
  const int m = cam.msaa_samples;
  if (m != 0 && m != 1 && m != 2 && m != 4 && m != 8) {
    c.Fail("camera.msaa_samples",
           "must be 0, 1, 2, 4 or 8 (llvmpipe renders at most 4), got " + std::to_string(m));
  }
  c.Positive(cam.near_m, "camera.near_m", " m");
  c.Positive(cam.far_m, "camera.far_m", " m");
  if (!(cam.far_m > cam.near_m)) {
    c.Fail("camera.far_m", "must be beyond camera.near_m = " + Checker::Num(cam.near_m) +
                               " m, got " + Checker::Num(cam.far_m));
  }
}

void CheckBoard(const Checker& c, const BoardSpec& b) {
  c.IntRange(b.robot, "board.robot", 0, kNumRobots - 1);
  c.IntAtLeast(b.squares_x, "board.squares_x", 2);
  c.IntAtLeast(b.squares_y, "board.squares_y", 2);
  c.Positive(b.square_m, "board.square_m", " m");
  c.NonNegative(b.margin_m, "board.margin_m", " m");
  c.Positive(b.thickness_m, "board.thickness_m", " m");
  c.NonNegative(b.mass_kg, "board.mass_kg", " kg");
  c.Rigid(b.X_FT, "board.X_FT");
}

void CheckPhysics(const Checker& c, const PhysicsSpec& p) {
  c.Positive(p.timestep_s, "physics.timestep_s", " s");
  c.Positive(p.stiffness, "physics.stiffness", " N m/rad");
  c.Positive(p.armature, "physics.armature", " kg m^2");
  c.Positive(p.max_joint_speed, "physics.max_joint_speed", " rad/s");
  c.Positive(p.settle_speed, "physics.settle_speed", " rad/s");
  c.IntAtLeast(p.settle_steps, "physics.settle_steps", 1);
  c.IntAtLeast(p.max_steps, "physics.max_steps", 1);
  if (p.max_steps < p.settle_steps) {
    c.Fail("physics.max_steps", "must be >= physics.settle_steps = " +
                                    std::to_string(p.settle_steps) + " (a move could never "
                                    "settle), got " + std::to_string(p.max_steps));
  }
}

void CheckEffect(const Checker& c, const EffectSpec& e, int k, const TwinSpec& spec) {
  const std::string field = "effects[" + std::to_string(k) + "]";
  if (e.type.empty()) c.Fail(field + ".type", "must name an effect type, got ''");
  c.IntRange(e.robot, field + ".robot", -1, kNumRobots - 1);
  // The joint must exist on every robot the effect acts on.
  int joints = kMaxJoints;
  for (int r = 0; r < kNumRobots; ++r) {
    if (e.robot == -1 || e.robot == r) joints = std::min(joints, spec.robots[r].model.num_joints());
  }
  c.IntRange(e.joint, field + ".joint", -1, joints - 1);
  for (const auto& [name, value] : e.params) c.Finite(value, field + ".params." + name);
}

}  // namespace

const char* ToString(Installation installation) {
  switch (installation) {
    case Installation::kFloor:
      return "floor";
    case Installation::kWall:
      return "wall";
    case Installation::kCeiling:
      return "ceiling";
  }
  return "unknown";
}

void ValidateTwinSpec(const TwinSpec& spec, const std::string& where) {
  const Checker c(where);
  for (int i = 0; i < kNumRobots; ++i) CheckRobot(c, spec.robots[i], i, where);
  CheckCamera(c, spec.camera);
  CheckBoard(c, spec.board);
  if (spec.camera.robot == spec.board.robot) {
    c.Fail("board.robot", "must differ from camera.robot (the camera and the board are on "
                          "different robots), got both " + std::to_string(spec.board.robot));
  }
  for (int i = 0; i < kNumRobots; ++i) {
    const TipSpec& t = spec.tips[i];
    const std::string field = "tips[" + std::to_string(i) + "]";
    c.Rigid(t.X_FTip, field + ".X_FTip");
    c.Positive(t.length_m, field + ".length_m", " m");
    c.Positive(t.radius_m, field + ".radius_m", " m");
  }
  CheckPhysics(c, spec.physics);
  for (std::size_t k = 0; k < spec.effects.size(); ++k) {
    CheckEffect(c, spec.effects[k], static_cast<int>(k), spec);
  }
}

}  // namespace twin
