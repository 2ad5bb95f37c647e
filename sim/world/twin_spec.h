// The description of a twin cell: everything sim/ needs to build the MuJoCo world, as plain
// structs (no MuJoCo, no YAML). bench/ fills it from a scenario file; sim/ never reads files.
// Frames (calib/common/frames.h): W world, B robot base, F flange (DH frame L6 of the true model),
// C camera (OpenCV optical frame), T board (origin at the feature point P), Tip measuring tip.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// The most robots a cell has. A cell has one or two (TwinSpec::num_robots); per-robot arrays
/// hold kMaxRobots entries, of which the first num_robots are the cell's.
constexpr int kMaxRobots = 2;

/// How a robot base is mounted (Gan et al. 2014): base z up, horizontal, or down.
enum class Installation { kFloor, kWall, kCeiling };

/// Name of an installation ("floor", "wall", "ceiling").
const char* ToString(Installation installation);

/// One arm of the cell.
/// A temperature sensor on a robot's structure, as controllers log one: it reads the cell's
/// ambient temperature plus the arm's own warming (the twin's thermal effects on that robot),
/// with noise per reading.
struct TemperatureSensorSpec {
  bool present = false;
  double ambient_C = 20.0;   ///< what it reads on the cold arm [deg C]
  double sigma_K = 0.1;      ///< noise per reading [K]
};

struct RobotSpec {
  KinematicModel model;                     ///< true geometry before geometry effects
  Installation installation = Installation::kFloor;
  Transform X_WB = Transform::Identity();   ///< base pose in the world
  JointVector q_initial = JointVector::Zero(kDefaultJoints);  ///< motor-side start angles [rad]
  TemperatureSensorSpec temperature_sensor; ///< absent unless present
};

/// Pinhole intrinsics in OpenCV's convention (pixel centres at integer coordinates).
struct Intrinsics {
  int width = 1024;     ///< [px]
  int height = 768;     ///< [px]
  double fx = 834.31;   ///< [px] (Zhu et al. 2019, section VI.A)
  double fy = 833.38;   ///< [px]
  double cx = 513.56;   ///< [px]
  double cy = 403.95;   ///< [px]
};

/// Brown-Conrady lens distortion, OpenCV's (k1, k2, p1, p2, k3); all zero means none.
struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool Any() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0; }
};

/// The hand camera, rigidly on one robot's flange.
struct CameraSpec {
  int robot = 0;                            ///< the active robot carrying the camera
  Transform X_FC = Transform::Identity();   ///< hand-eye: camera optical frame in the flange
  Intrinsics intrinsics;
  Distortion distortion;
  int msaa_samples = 4;                     ///< off-screen multisampling (llvmpipe clamps to 4)
  /// Draw the sky behind the scene (the default); false: the background is black and a frame
  /// costs about a quarter less to render. Its paired study: docs/results/paired_studies.md.
  bool skybox = true;
  double near_m = 0.02;                     ///< near clipping plane [m]
  double far_m = 5.0;                       ///< far clipping plane [m]
};

/// The chessboard on the passive robot's flange. Board frame T: origin at the feature point P
/// (the centre inner corner), on the printed face, z out of the face, x along a row of squares.
struct BoardSpec {
  int robot = 1;                            ///< the passive robot carrying the board
  int squares_x = 4;                        ///< squares along x (inner corners: squares - 1)
  int squares_y = 4;                        ///< squares along y
  double square_m = 0.02;                   ///< side of one square [m]
  double margin_m = 0.01;                   ///< white border around the squares [m]
  double thickness_m = 0.004;               ///< plate thickness [m]
  double mass_kg = 0.2;                     ///< mass of board and bracket [kg]
  Transform X_FT = Transform::Identity();   ///< board frame in the flange
};

/// A measuring tip on a flange for handclasp contacts (Gan et al. 2014).
struct TipSpec {
  Transform X_FTip = Transform::Identity();  ///< tip point frame in the flange (origin = tip)
  double length_m = 0.08;                    ///< tip body length behind the point [m]
  double radius_m = 0.004;                   ///< tip radius [m]
};

/// Joint drive and settling. Without the compliance effect the drive holds the link exactly at
/// its target (gravity is fed forward); with it the link sags by gravity torque / stiffness.
struct PhysicsSpec {
  double timestep_s = 0.002;        ///< physics step [s]
  double stiffness = 1e5;           ///< position-actuator gain kp [N m/rad]
  double armature = 0.1;            ///< reflected rotor inertia per joint [kg m^2]
  double max_joint_speed = 1.0;     ///< speed of the commanded ramp [rad/s]
  double settle_speed = 1e-6;       ///< settled when every joint is slower than this [rad/s]
  int settle_steps = 20;            ///< ... for this many consecutive steps
  int max_steps = 20000;            ///< step limit of one move (settling included)
  bool gravity = true;              ///< gravity on (9.81 m/s^2 along -z of the world)
};

/// One effect on the truth side: `type` names it, `params` are its numbers, keyed with units
/// in the key (e.g. "amplitude_deg"); an effect checks its own keys.
struct EffectSpec {
  std::string type;                       ///< e.g. "transmission_error"
  bool declared = true;                   ///< false: the estimator is not told about it
  int robot = -1;                         ///< 0..num_robots-1, or -1 for every robot
  int joint = -1;                         ///< 0..5, or -1 for every joint
  std::map<std::string, double> params;   ///< numbers by name
  std::string where;                      ///< where it was written, for messages
};

/// A laser tracker watching a reflector (SMR) on one robot's flange: the truth of the tracker
/// sensor (the estimator is told neither the tracker's pose nor the true reflector offset).
/// A reading is the reflector's position in the tracker frame plus Gaussian noise of sigma
/// sigma_m + sigma_per_m * range per axis, plus drift_m_per_s times the cell's clock.
struct TrackerSpec {
  bool present = false;
  int robot = 1;                               ///< the robot carrying the reflector
  Transform X_WT = Transform::Identity();      ///< the tracker frame in the world
  Vector3 p_FR = Vector3::Zero();              ///< the reflector in the flange frame [m]
  double sigma_m = 1e-5;                       ///< noise per axis [m]
  double sigma_per_m = 0.0;                    ///< range-proportional noise [m per m of range]
  Vector3 drift_m_per_s = Vector3::Zero();     ///< drift of the readings [m/s]
  double max_range_m = 30.0;                   ///< beyond it: out of range [m]
};

/// A whole twin cell: two robots with the hand camera on one flange and the board on the
/// other (the optical-axis and handclasp cells), or one robot alone (a laser-tracker cell),
/// without camera, board or intrinsics target.
struct TwinSpec {
  int num_robots = kMaxRobots;             ///< 1 or 2: robots[0..num_robots) are the cell's
  std::array<RobotSpec, kMaxRobots> robots;
  CameraSpec camera;                       ///< the hand camera; unused with one robot
  BoardSpec board;                         ///< the board; unused with one robot
  /// A larger chessboard the operator can mount on the board's bracket in place of the board
  /// for the camera's intrinsic calibration (TwinCell::MountTarget); its robot field is
  /// ignored (it goes where the board is). Absent: the cell has only the board. Never on a
  /// one-robot cell.
  std::optional<BoardSpec> intrinsics_target;
  std::array<TipSpec, kMaxRobots> tips;    ///< tips[0..num_robots) are the cell's
  PhysicsSpec physics;
  std::vector<EffectSpec> effects;
  TrackerSpec tracker;                    ///< a laser tracker, if present
  std::uint64_t seed = 1;                 ///< seed of every random effect
  /// Seed of the draws made while the cell runs (encoder, image, tracker and temperature noise,
  /// the operator's error); absent: `seed`. The geometry and the effects' magnitudes always
  /// come from `seed`, so two cells differing only here are one truth measured twice.
  std::optional<std::uint64_t> noise_seed;

  /// True for a two-robot cell: it has the hand camera and the board (camera, board); a
  /// one-robot cell has neither.
  bool HasCameraAndBoard() const { return num_robots == kMaxRobots; }
};

/// Checks values before anything is built; throws InputError naming `where`, the field and the
/// bad value (e.g. a negative square size, a zero focal length, a bad robot index). A
/// one-robot cell is checked without camera and board, and refuses an intrinsics target.
void ValidateTwinSpec(const TwinSpec& spec, const std::string& where);

}  // namespace twin
