#include "sim/world/twin_spec.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

#include "calib/common/errors.h"
#include "calib/common/text_format.h"
#include "sim/world/mjcf_writer.h"

namespace twin {
namespace {

// Largest angle between a base z axis and the direction its installation implies [deg].
constexpr double kInstallationToleranceDeg = 5.0;

// ---- Plausibility limits (issue 14): finite but absurd values are refused, each for a reason.
// Robot 1's base in the world: a cell is a few metres across; beyond 100 m MuJoCo's single
// precision rendering loses millimetres.
constexpr double kMaxWorldOffsetM = 100.0;
// Base-to-base distance: two arms that touch each other's tips or see each other's flange
// stand within a few metres (reach about 1-4 m each).
constexpr double kMaxBaseDistanceM = 20.0;
// Image size: the chessboard detector needs several pixels per square, impossible below
// 16 px; above 4096 px one frame needs more than 64 MiB and OSMesa's buffers.
constexpr int kMinImageSidePx = 16;
constexpr int kMaxImageSidePx = 4096;
// Focal length relative to the image width: fx = width / 20 is a 175 deg field of view (no
// pinhole lens sees more), fx = 50 x width a 1.1 deg one (a telescope, not a hand camera).
constexpr double kMinFocalPerWidth = 0.05;
constexpr double kMaxFocalPerWidth = 50.0;
// Pixel aspect fy / fx: sensor pixels are square to a few per cent; 2:1 is a unit mistake.
constexpr double kMaxPixelAspect = 2.0;
// Brown-Conrady coefficients: real lenses have |k| below ~1 and |p| below ~0.01; beyond these
// the polynomial folds over inside the image and the model describes no lens.
constexpr double kMaxRadialDistortion = 10.0;
constexpr double kMaxTangentialDistortion = 0.1;
// Clipping planes: nearer than 1 mm leaves the depth buffer without precision (far / near is
// then at most 1e5); beyond 100 m nothing of the cell is seen.
constexpr double kMinNearM = 0.001;
constexpr double kMaxFarM = 100.0;
// Tools on a flange (camera, board, tips): brackets longer than 1 m are not flange tools.
constexpr double kMaxToolOffsetM = 1.0;
// Board: 2 to 30 squares per side (the detector's time grows with the pattern; 29 x 29 inner
// corners is far beyond any flange-mounted target); at kBoardViewDistanceM, the far end of a
// hand camera's working range, a square must image to at least one pixel and the whole board
// must fit in the view, else it is either invisible or never seen whole.
constexpr int kMaxBoardSquares = 30;
constexpr double kBoardViewDistanceM = 2.0;
constexpr double kMaxBoardMarginM = 0.5;
constexpr double kMaxBoardThicknessM = 0.1;
// Flange payloads of arms of this class are 5-20 kg.
constexpr double kMaxToolMassKg = 20.0;
// Tips: a measuring tip is at most a metre long and a few centimetres thick.
constexpr double kMaxTipLengthM = 1.0;
constexpr double kMaxTipRadiusM = 0.05;
// Physics: steps above 10 ms make the stiff position servos unstable; below 10 us a move
// takes millions of steps. Gains, armatures and speeds span every industrial drive.
constexpr double kMinTimestepS = 1e-5;
constexpr double kMaxTimestepS = 0.01;
constexpr double kMinStiffness = 10.0;        // [N m/rad]
constexpr double kMaxStiffness = 1e8;         // [N m/rad]
constexpr double kMinArmature = 1e-4;         // [kg m^2]
constexpr double kMaxArmature = 100.0;        // [kg m^2]
constexpr double kMinJointSpeed = 0.01;       // [rad/s]
constexpr double kMaxJointSpeed = 20.0;       // [rad/s], about 1150 deg/s
// Settling: tests/sim/closed_loop/terms_vs_twin_test.cc settles to 1e-10 rad/s (measured), so
// the floor is below that, at 1e-12 rad/s (double rounding of the joint velocities); a move is bounded by max_steps, itself bounded so
// that one move is at most 10^6 steps and 600 s of simulated time (any move settles in
// seconds), which keeps every run's physics linear in its number of moves.
constexpr double kMinSettleSpeed = 1e-12;     // [rad/s]
constexpr int kMaxSettleSteps = 10000;
constexpr int kMaxMoveSteps = 1000000;
constexpr double kMaxMoveSimulatedS = 600.0;

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
  // A finite value in [lo, hi] (in SI, printed as `unit`); `why` gives the limit's reason.
  void Within(double v, const std::string& field, double lo, double hi, const std::string& unit,
              const std::string& why) const {
    if (std::isfinite(v) && v >= lo && v <= hi) return;
    Fail(field, "must be in [" + Num(lo) + ", " + Num(hi) + "]" + unit + " (" + why + "), got " +
                    Num(v) + unit);
  }
  // |translation| of a transform at most max_m.
  void Offset(const Transform& X, const std::string& field, double max_m,
              const std::string& why) const {
    const double r = X.translation().norm();
    if (r <= max_m) return;
    Fail(field, "translation must be at most " + Num(max_m) + " m long (" + why + "), got " +
                    Num(r) + " m");
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
  c.Offset(robot.X_WB, RobotField(i, "X_WB"), kMaxWorldOffsetM,
           "a cell is a few metres across");
  if (robot.q_initial.size() != robot.model.num_joints()) {
    c.Fail(RobotField(i, "q_initial"), "must hold " + std::to_string(robot.model.num_joints()) +
                                           " joint angles (one per joint of " +
                                           robot.model.name + "), got " +
                                           std::to_string(robot.q_initial.size()));
  }
  if (robot.temperature_sensor.present) {
    // Bounds: a working cell's air; a sensor noisier than 10 K is no thermometer.
    const double ambient = robot.temperature_sensor.ambient_C;
    if (!(ambient >= -40.0 && ambient <= 80.0)) {
      c.Fail(RobotField(i, "temperature_sensor.ambient_C"),
             "must be -40 to 80 deg C, got " + Checker::Num(ambient));
    }
    const double sigma = robot.temperature_sensor.sigma_K;
    if (!(sigma >= 0.0 && sigma <= 10.0)) {
      c.Fail(RobotField(i, "temperature_sensor.sigma_K"),
             "must be 0 to 10 K, got " + Checker::Num(sigma));
    }
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

// A point p_F on a flange (frame F = L_N of `model`) that lies inside the flange disc or the
// last link behind it: within the disc radius of the flange axis and behind its face (the
// link's d points from the wrist to the face).
bool InsideFlange(const KinematicModel& model, const Vector3& p_F) {
  const double behind = model.flange().dh.d >= 0.0 ? -p_F.z() : p_F.z();
  return std::hypot(p_F.x(), p_F.y()) < FlangeRadius(model.num_joints()) && behind > 0.0;
}

void CheckFlangeTool(const Checker& c, const TwinSpec& spec, int robot, const Transform& X_F,
                     const std::string& field, const std::string& what) {
  c.Offset(X_F, field, kMaxToolOffsetM, "a flange tool's bracket is shorter than a metre");
  if (robot < 0 || robot >= spec.num_robots) return;
  const KinematicModel& m = spec.robots[robot].model;
  if (m.num_joints() < 1 || !InsideFlange(m, X_F.translation())) return;
  const Vector3 p = 1e3 * X_F.translation();
  const auto N = [](double v) { return Checker::Num(v); };
  c.Fail(field, "puts " + what + " at (" + N(p.x()) + ", " + N(p.y()) + ", " + N(p.z()) +
                    ") mm in the flange frame, inside the flange (radius " +
                    N(1e3 * FlangeRadius(m.num_joints())) + " mm, behind its face at z = 0)");
}

void CheckCamera(const Checker& c, const CameraSpec& cam) {
  c.IntRange(cam.robot, "camera.robot", 0, kMaxRobots - 1);
  c.Rigid(cam.X_FC, "camera.X_FC");
  const Intrinsics& in = cam.intrinsics;
  c.IntRange(in.width, "camera.intrinsics.width", kMinImageSidePx, kMaxImageSidePx);
  c.IntRange(in.height, "camera.intrinsics.height", kMinImageSidePx, kMaxImageSidePx);
  c.Positive(in.fx, "camera.intrinsics.fx", " px");
  c.Positive(in.fy, "camera.intrinsics.fy", " px");
  c.Within(in.fx, "camera.intrinsics.fx", kMinFocalPerWidth * in.width,
           kMaxFocalPerWidth * in.width, " px",
           "0.05 to 50 times the image width: fields of view from 175 to 1.1 deg");
  c.Within(in.fy / in.fx, "camera.intrinsics.fy", 1.0 / kMaxPixelAspect, kMaxPixelAspect,
           " x fx", "pixels are square to a few per cent");
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
  for (const auto& [v, name] : {std::pair<double, const char*>{d.k1, "k1"}, {d.k2, "k2"},
                                {d.p1, "p1"}, {d.p2, "p2"}, {d.k3, "k3"}}) {
    c.Finite(v, std::string("camera.distortion.") + name);
  }
  const std::string radial = "beyond it the Brown-Conrady polynomial describes no lens";
  c.Within(d.k1, "camera.distortion.k1", -kMaxRadialDistortion, kMaxRadialDistortion, "", radial);
  c.Within(d.k2, "camera.distortion.k2", -kMaxRadialDistortion, kMaxRadialDistortion, "", radial);
  c.Within(d.k3, "camera.distortion.k3", -kMaxRadialDistortion, kMaxRadialDistortion, "", radial);
  const std::string tangential = "a real lens is decentred by far less";
  c.Within(d.p1, "camera.distortion.p1", -kMaxTangentialDistortion, kMaxTangentialDistortion, "",
           tangential);
  c.Within(d.p2, "camera.distortion.p2", -kMaxTangentialDistortion, kMaxTangentialDistortion, "",
           tangential);
  const int m = cam.msaa_samples;
  if (m != 0 && m != 1 && m != 2 && m != 4 && m != 8) {
    c.Fail("camera.msaa_samples",
           "must be 0, 1, 2, 4 or 8 (llvmpipe renders at most 4), got " + std::to_string(m));
  }
  c.Positive(cam.near_m, "camera.near_m", " m");
  c.Positive(cam.far_m, "camera.far_m", " m");
  c.Within(cam.near_m, "camera.near_m", kMinNearM, kMaxFarM, " m",
           "nearer than 1 mm leaves the depth buffer without precision");
  c.Within(cam.far_m, "camera.far_m", kMinNearM, kMaxFarM, " m",
           "nothing of the cell is farther than 100 m");
  if (!(cam.far_m > cam.near_m)) {
    c.Fail("camera.far_m", "must be beyond camera.near_m = " + Checker::Num(cam.near_m) +
                               " m, got " + Checker::Num(cam.far_m));
  }
}

// The plate of a board or target: `field` names the spec field ("board", "intrinsics_target").
void CheckBoard(const Checker& c, const BoardSpec& b, const CameraSpec& cam,
                const std::string& field) {
  c.IntRange(b.squares_x, field + ".squares_x", 2, kMaxBoardSquares);
  c.IntRange(b.squares_y, field + ".squares_y", 2, kMaxBoardSquares);
  c.Positive(b.square_m, field + ".square_m", " m");
  // At kBoardViewDistanceM a square of s images to fx s / D pixels; the view is
  // D width / fx by D height / fy.
  const Intrinsics& k = cam.intrinsics;
  if (k.fx > 0.0 && k.fy > 0.0) {
    const double smallest = kBoardViewDistanceM / std::min(k.fx, k.fy);
    const double view = kBoardViewDistanceM * std::min(k.width / k.fx, k.height / k.fy);
    c.Within(b.square_m, field + ".square_m", smallest, view, " m",
             "at 2 m from the camera a square must image to at least one pixel and fit in "
             "the view");
    const double side = std::max(b.squares_x, b.squares_y) * b.square_m + 2.0 * b.margin_m;
    if (side > view) {
      c.Fail(field + ".square_m", "makes the board " + Checker::Num(side) + " m across, larger "
                               "than the camera's view at 2 m (" + Checker::Num(view) +
                               " m): it is never seen whole");
    }
  }
  c.NonNegative(b.margin_m, field + ".margin_m", " m");
  c.Within(b.margin_m, field + ".margin_m", 0.0, kMaxBoardMarginM, " m",
           "a white border, not a wall");
  c.Positive(b.thickness_m, field + ".thickness_m", " m");
  c.Within(b.thickness_m, field + ".thickness_m", 0.0, kMaxBoardThicknessM, " m",
           "a plate, not a block");
  c.NonNegative(b.mass_kg, field + ".mass_kg", " kg");
  c.Within(b.mass_kg, field + ".mass_kg", 0.0, kMaxToolMassKg, " kg",
           "flange payloads of such arms are 5-20 kg");
  c.Rigid(b.X_FT, field + ".X_FT");
}

void CheckPhysics(const Checker& c, const PhysicsSpec& p) {
  c.Positive(p.timestep_s, "physics.timestep_s", " s");
  c.Within(p.timestep_s, "physics.timestep_s", kMinTimestepS, kMaxTimestepS, " s",
           "longer steps make the stiff servos unstable, shorter ones a move endless");
  c.Positive(p.stiffness, "physics.stiffness", " N m/rad");
  c.Within(p.stiffness, "physics.stiffness", kMinStiffness, kMaxStiffness, " N m/rad",
           "the range of industrial position servos");
  c.Positive(p.armature, "physics.armature", " kg m^2");
  c.Within(p.armature, "physics.armature", kMinArmature, kMaxArmature, " kg m^2",
           "the range of reflected rotor inertias");
  c.Positive(p.max_joint_speed, "physics.max_joint_speed", " rad/s");
  c.Within(p.max_joint_speed, "physics.max_joint_speed", kMinJointSpeed, kMaxJointSpeed,
           " rad/s", "industrial joints move at 0.5 to 1150 deg/s");
  c.Positive(p.settle_speed, "physics.settle_speed", " rad/s");
  c.Within(p.settle_speed, "physics.settle_speed", kMinSettleSpeed, p.max_joint_speed,
           " rad/s", "below 1e-12 rad/s the integrator's rounding never settles; above the joint speed "
           "nothing is settling");
  c.IntAtLeast(p.settle_steps, "physics.settle_steps", 1);
  c.IntRange(p.settle_steps, "physics.settle_steps", 1, kMaxSettleSteps);
  c.IntAtLeast(p.max_steps, "physics.max_steps", 1);
  c.IntRange(p.max_steps, "physics.max_steps", 1, kMaxMoveSteps);
  if (p.max_steps * p.timestep_s > kMaxMoveSimulatedS) {
    c.Fail("physics.max_steps", "times physics.timestep_s must be at most " +
                                    Checker::Num(kMaxMoveSimulatedS) + " s of simulated time "
                                    "per move (any move settles in seconds; this bounds every "
                                    "run), got " + Checker::Num(p.max_steps * p.timestep_s) +
                                    " s");
  }
  if (p.max_steps < p.settle_steps) {
    c.Fail("physics.max_steps", "must be >= physics.settle_steps = " +
                                    std::to_string(p.settle_steps) + " (a move could never "
                                    "settle), got " + std::to_string(p.max_steps));
  }
}

void CheckEffect(const Checker& c, const EffectSpec& e, int k, const TwinSpec& spec) {
  const std::string field = "effects[" + std::to_string(k) + "]";
  if (e.type.empty()) c.Fail(field + ".type", "must name an effect type, got ''");
  c.IntRange(e.robot, field + ".robot", -1, spec.num_robots - 1);
  // The joint must exist on every robot the effect acts on.
  int joints = kMaxJoints;
  for (int r = 0; r < spec.num_robots; ++r) {
    if (e.robot == -1 || e.robot == r) joints = std::min(joints, spec.robots[r].model.num_joints());
  }
  c.IntRange(e.joint, field + ".joint", -1, joints - 1);
  for (const auto& [name, value] : e.params) c.Finite(value, field + ".params." + name);
}

// The hand camera, the board and the intrinsics target of a two-robot cell, where they sit
// and how far apart the two bases stand.
void CheckCameraAndBoard(const Checker& c, const TwinSpec& spec) {
  CheckCamera(c, spec.camera);
  c.IntRange(spec.board.robot, "board.robot", 0, kMaxRobots - 1);  // the target's is ignored
  CheckBoard(c, spec.board, spec.camera, "board");
  if (spec.intrinsics_target) {
    CheckBoard(c, *spec.intrinsics_target, spec.camera, "intrinsics_target");
  }
  const Vector3 p_B1B2 =
      (spec.robots[0].X_WB.inverse() * spec.robots[1].X_WB).translation();
  if (p_B1B2.norm() > kMaxBaseDistanceM) {
    c.Fail(RobotField(1, "X_WB"), "puts robot 2's base " + Checker::Num(p_B1B2.norm()) +
                                      " m from robot 1's, more than " +
                                      Checker::Num(kMaxBaseDistanceM) +
                                      " m (two arms that must reach or see each other stand "
                                      "within a few metres)");
  }
  CheckFlangeTool(c, spec, spec.camera.robot, spec.camera.X_FC, "camera.X_FC",
                  "the camera's optical centre");
  CheckFlangeTool(c, spec, spec.board.robot, spec.board.X_FT, "board.X_FT",
                  "the board's feature point");
  if (spec.intrinsics_target) {
    CheckFlangeTool(c, spec, spec.board.robot, spec.intrinsics_target->X_FT,
                    "intrinsics_target.X_FT", "the intrinsics target's centre");
  }
  if (spec.camera.robot == spec.board.robot) {
    c.Fail("board.robot", "must differ from camera.robot (the camera and the board are on "
                          "different robots), got both " + std::to_string(spec.board.robot));
  }
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

// The tracker (plausibility): a laser tracker measures to about 80 m with micrometres of noise;
// a reflector sits on a short bracket; a drift beyond 1 um/s would be a broken instrument.
static void CheckTracker(const Checker& c, const TrackerSpec& t, int num_robots) {
  if (!t.present) return;
  c.IntRange(t.robot, "tracker.robot", 0, num_robots - 1);
  c.Rigid(t.X_WT, "tracker.X_WT");
  c.Offset(t.X_WT, "tracker.X_WT", kMaxWorldOffsetM, "a tracker stands in the cell");
  if (!(t.p_FR.allFinite() && t.p_FR.norm() <= 0.5)) {
    c.Fail("tracker.reflector", "must lie within 500 mm of the flange (a reflector's bracket), "
                                "got " + Checker::Num(t.p_FR.norm()) + " m");
  }
  c.Within(t.sigma_m, "tracker.sigma", 0.0, 1e-3, " m", "a laser tracker measures to microns");
  c.Within(t.sigma_per_m, "tracker.sigma_per_m", 0.0, 1e-4, " m/m",
           "a tracker's range-proportional error is a few um per m");
  if (!(t.drift_m_per_s.allFinite() && t.drift_m_per_s.norm() <= 1e-6)) {
    c.Fail("tracker.drift", "must be at most 1 um/s (3.6 mm/h), got " +
                                Checker::Num(t.drift_m_per_s.norm()) + " m/s");
  }
  c.Within(t.max_range_m, "tracker.max_range", 0.1, 80.0, " m", "trackers reach about 80 m");
}

void ValidateTwinSpec(const TwinSpec& spec, const std::string& where) {
  const Checker c(where);
  c.IntRange(spec.num_robots, "num_robots", 1, kMaxRobots);
  for (int i = 0; i < spec.num_robots; ++i) CheckRobot(c, spec.robots[i], i, where);
  CheckTracker(c, spec.tracker, spec.num_robots);
  if (spec.HasCameraAndBoard()) {
    CheckCameraAndBoard(c, spec);
  } else if (spec.intrinsics_target) {
    c.Fail("intrinsics_target", "must be absent on a one-robot cell (it has no board, and no "
                                "camera to calibrate)");
  }
  for (int i = 0; i < spec.num_robots; ++i) {
    const TipSpec& t = spec.tips[i];
    const std::string field = "tips[" + std::to_string(i) + "]";
    c.Rigid(t.X_FTip, field + ".X_FTip");
    CheckFlangeTool(c, spec, i, t.X_FTip, field + ".X_FTip", "the tip point");
    c.Positive(t.length_m, field + ".length_m", " m");
    c.Within(t.length_m, field + ".length_m", 0.0, kMaxTipLengthM, " m",
             "a measuring tip, not a boom");
    c.Positive(t.radius_m, field + ".radius_m", " m");
    c.Within(t.radius_m, field + ".radius_m", 0.0, kMaxTipRadiusM, " m",
             "a tip is a few millimetres thick");
  }
  CheckPhysics(c, spec.physics);
  for (std::size_t k = 0; k < spec.effects.size(); ++k) {
    CheckEffect(c, spec.effects[k], static_cast<int>(k), spec);
  }
}

}  // namespace twin
