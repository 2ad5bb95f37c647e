#include "bench/io/scenario_keys.h"

#include <stdexcept>

#include "calib/kinematics/kinematic_model.h"
#include "sim/effects/effect.h"
#include "sim/world/twin_spec.h"

namespace twin {
namespace {

ScenarioKey K(std::string key, KeyType type) {
  ScenarioKey k;
  k.key = std::move(key);
  k.type = type;
  return k;
}

using T = KeyType;

std::vector<ScenarioKey> PlateKeys() {
  return {
      K("squares", T::kIntegers).Required().Count(2).Min(2).Doc("[x, y] squares of the chessboard"),
      K("square_mm", T::kNumber).Required().Unit("mm").Above(0).Doc("side of one square"),
      K("margin_mm", T::kNumber).Unit("mm").Default("10").Min(0)
          .Doc("white margin around the squares"),
      K("thickness_mm", T::kNumber).Unit("mm").Default("4").Above(0).Doc("plate thickness"),
      K("mass_kg", T::kNumber).Unit("kg").Default("0.2").Min(0).Doc("plate mass"),
  };
}

std::vector<ScenarioSection> MakeSections() {
  std::vector<ScenarioSection> s;
  s.push_back({"root", "A twinbench scenario file: one digital-twin cell and its procedures "
                       "(docs/reference/scenario.md).",
               {K("scenario", T::kSection).Required().Of("scenario").Doc("the scenario")}});
  s.push_back(
      {"scenario", "The twin cell: robots, camera, board, effects, and the procedures to run. "
                   "Two robots carry the camera and the board; one robot alone is a laser-tracker "
                   "cell (tracker and tracker_calibration; no camera, board, intrinsics_target, "
                   "calibration or handclasp).",
       {K("format", T::kInteger).Min(1).Max(kScenarioFormat).Default("1")
            .Doc("the scenario format version. 1: every file without this key. 2: adds this "
                 "key; `twinbench check` validates a format-2 file strictly against this schema "
                 "(a quoted \"834\" is a string, not a number; a string that reads as a number "
                 "or true/false must be quoted). A newer version than the tool knows is refused."),
        K("name", T::kString).Required().Doc("the scenario's name (non-empty)"),
        K("seed", T::kUnsigned).Default("1").Doc("the seed of both random streams (truth and "
                                                 "estimator); not with seeds"),
        K("seeds", T::kSection).Of("seeds").Doc("the two random streams apart; not with seed"),
        K("robots", T::kSectionList).Required().Counts(1, kMaxRobots)
            .Doc("one or two robots: robot 1 (with base), robot 2 (with base_from_robot1); one "
                 "robot alone is a laser-tracker cell"),
        K("camera", T::kSection).Of("camera").RequiredWithRobots(2).OnlyWithRobots(2)
            .Doc("the hand camera (truth)"),
        K("board", T::kSection).Of("board").RequiredWithRobots(2).OnlyWithRobots(2)
            .Doc("the chessboard (truth)"),
        K("intrinsics_target", T::kSection).Of("intrinsics_target").OnlyWithRobots(2)
            .Doc("a larger chessboard swapped onto the board's bracket for the intrinsics step"),
        K("tips", T::kSectionMap).Of("tip").Doc("tips keyed by robot name"),
        K("physics", T::kSection).Of("physics").Doc("joint drive and settling"),
        K("effects", T::kSectionList).Of("effect").Doc("effects applied on the truth side"),
        K("tracker", T::kSection).Of("tracker").Doc("a laser tracker (truth)"),
        K("calibration", T::kOpaque).OnlyWithRobots(2)
            .Doc("the optical-axis procedure (bench/io/calibration_config.h)"),
        K("handclasp", T::kOpaque).OnlyWithRobots(2)
            .Doc("the handclasp base-frame procedure (bench/runs/handclasp_run.h)"),
        K("tracker_calibration", T::kOpaque).RequiredWithRobots(1)
            .Doc("the tracker procedure (bench/runs/tracker_run.h)"),
        K("acceptance", T::kOpaque).Doc("criteria on report.json figures "
                                        "(bench/report/acceptance.h)")}});
  s.back().keys[4].tuple = {"robot1", "robot2"};
  s.back().keys.back().opaque_list = true;
  s.push_back({"seeds", "The two independent random streams (trial t of a study adds t).",
               {K("truth", T::kUnsigned).Default("1").Doc("the twin's draws"),
                K("estimator", T::kUnsigned).Default("1").Doc("the estimator's own randomness")}});
  const auto robot = [](bool first) {
    std::vector<ScenarioKey> keys = {
        K("name", T::kString).Required()
            .Doc("unique identifier ([A-Za-z_][A-Za-z0-9_]*), used by camera.robot, board.robot, "
                 "tips and effects"),
        K("model", T::kString).Required().Doc("model file (.yaml, .yml or .urdf), relative to "
                                              "the scenario"),
        K("base_link", T::kString).Doc("URDF only: where the arm starts (default: the root)"),
        K("tip_link", T::kString).Doc("URDF only: where the arm ends (default: the leaf link "
                                      "with the most moving joints above it)"),
        K("installation", T::kString).Required().OneOf({"floor", "wall", "ceiling"})
            .Doc("how the base is mounted")};
    if (first) {
      keys.push_back(K("base", T::kSection).Of("pose").Default("identity").Doc("X_WB1"));
    } else {
      keys.push_back(K("base_from_robot1", T::kSection).Required().Of("pose")
                         .Doc("X_B1B2; X_WB2 = X_WB1 X_B1B2"));
    }
    keys.push_back(K("initial_joints_deg", T::kNumbers).Required().Unit("deg")
                       .Counts(1, kMaxJoints).Doc("motor-side angles, one per joint"));
    keys.push_back(K("temperature_sensor", T::kSection).Of("temperature_sensor")
                       .Doc("a temperature sensor on the arm"));
    return keys;
  };
  s.push_back({"robot1", "Robot 1 (the first item of robots).", robot(true)});
  s.push_back({"robot2", "Robot 2 (the second item of robots).", robot(false)});
  s.push_back({"temperature_sensor", "A temperature sensor on the arm.",
               {K("ambient_C", T::kNumber).Unit("C").Min(-40).Max(80).Doc("ambient temperature"),
                K("sigma_K", T::kNumber).Unit("K").Min(0).Max(10).Doc("noise of a reading")}});
  s.push_back({"pose", "A pose: xyz_mm and exactly one of rpy_deg (fixed axes, R = Rz(y) Ry(p) "
                       "Rx(r), as URDF) or zyz_deg (R = Rz(a) Ry(b) Rz(c)).",
               {K("xyz_mm", T::kNumbers).Required().Unit("mm").Count(3).Doc("translation"),
                K("rpy_deg", T::kNumbers).Unit("deg").Count(3).Min(-360).Max(360)
                    .Doc("roll, pitch, yaw about fixed axes"),
                K("zyz_deg", T::kNumbers).Unit("deg").Count(3).Min(-360).Max(360)
                    .Doc("Euler angles z, y, z")},
               false,
               {{"rpy_deg", "zyz_deg"}}});
  s.push_back(
      {"camera", "The hand camera (OpenCV pinhole model).",
       {K("robot", T::kString).Required().Doc("the robot whose flange carries it"),
        K("hand_eye", T::kSection).Required().Of("pose").Doc("X_FC (OpenCV optical frame C)"),
        K("resolution", T::kIntegers).Required().Unit("px").Count(2).Doc("[width, height]"),
        K("fx", T::kNumber).Required().Unit("px").Above(0).Doc("focal length x"),
        K("fy", T::kNumber).Required().Unit("px").Above(0).Doc("focal length y"),
        K("cx", T::kNumber).Required().Unit("px").Doc("principal point x"),
        K("cy", T::kNumber).Required().Unit("px").Doc("principal point y"),
        K("distortion", T::kNumbers).Count(5).Default("none").Doc("[k1, k2, p1, p2, k3]"),
        K("msaa", T::kInteger).OneOfIntegers({0, 1, 2, 4, 8}).Default("4")
            .Doc("anti-aliasing samples"),
        K("near_mm", T::kNumber).Unit("mm").Above(0).Default("20").Doc("near clipping plane"),
        K("far_mm", T::kNumber).Unit("mm").Above(0).Default("5000").Doc("far clipping plane")}});
  {
    std::vector<ScenarioKey> board = {K("robot", T::kString).Required()
                                          .Doc("the robot whose flange carries it")};
    for (const ScenarioKey& k : PlateKeys()) board.push_back(k);
    board.push_back(K("mount", T::kSection).Required().Of("pose").Doc("X_FT"));
    s.push_back({"board", "The chessboard the camera sees.", board});
  }
  {
    std::vector<ScenarioKey> target = PlateKeys();
    target.push_back(K("mount", T::kSection).Of("pose").Default("the board's mount").Doc("X_FT"));
    s.push_back({"intrinsics_target", "A larger chessboard for the intrinsics step (defaults: "
                                      "the board's mass and mount).",
                 target});
  }
  s.push_back({"tip", "A robot's tip: a pose X_FTip (xyz_mm and a rotation, or none: at the "
                      "flange's centre) and its capsule.",
               {K("xyz_mm", T::kNumbers).Unit("mm").Count(3).Doc("tip point in the flange"),
                K("rpy_deg", T::kNumbers).Unit("deg").Count(3).Min(-360).Max(360)
                    .Doc("roll, pitch, yaw"),
                K("zyz_deg", T::kNumbers).Unit("deg").Count(3).Min(-360).Max(360)
                    .Doc("Euler angles z, y, z"),
                K("length_mm", T::kNumber).Unit("mm").Default("80").Doc("body length behind the "
                                                                         "point"),
                K("radius_mm", T::kNumber).Unit("mm").Default("4").Doc("tip radius")}});
  s.push_back(
      {"physics", "Joint drive and settling.",
       {K("timestep_s", T::kNumber).Unit("s").Above(0).Default("0.002").Doc("physics step"),
        K("stiffness_Nm_per_rad", T::kNumber).Unit("N m/rad").Above(0).Default("1e5")
            .Doc("position-actuator gain"),
        K("armature_kgm2", T::kNumber).Unit("kg m^2").Above(0).Default("0.1")
            .Doc("reflected rotor inertia per joint"),
        K("max_joint_speed_deg_s", T::kNumber).Unit("deg/s").Above(0).Default("57.3")
            .Doc("speed of the commanded ramp"),
        K("settle_speed_deg_s", T::kNumber).Unit("deg/s").Above(0).Default("5.7e-5")
            .Doc("settled when every joint is slower"),
        K("settle_steps", T::kInteger).Min(1).Default("20").Doc("... for this many steps"),
        K("max_steps", T::kInteger).Min(1).Default("20000").Doc("step limit of one move"),
        K("gravity", T::kBoolean).Default("true").Doc("gravity on")}});
  s.push_back({"effect", "An effect on the truth side; every other key is a number, a "
                         "parameter of the effect under its own name.",
               {K("type", T::kString).Required().OneOf(EffectTypes()).Doc("the effect"),
                K("declared", T::kBoolean).Default("true").Doc("told to the estimator?"),
                K("robot", T::kString).Default("every robot").Doc("robot name"),
                K("joint", T::kInteger).Min(1).Max(kMaxJoints).Default("every joint")
                    .Doc("joint 1..N")},
               true});
  s.push_back(
      {"tracker", "A laser tracker (truth).",
       {K("robot", T::kString).Required().Doc("the robot carrying the reflector"),
        K("pose", T::kSection).Required().Of("pose").Doc("the tracker frame in the world"),
        K("reflector_mm", T::kNumbers).Required().Unit("mm").Count(3)
            .Doc("the reflector in that robot's flange frame"),
        K("sigma_mm", T::kNumber).Unit("mm").Default("0.01").Doc("noise per axis"),
        K("sigma_um_per_m", T::kNumber).Unit("um/m").Default("0").Doc("range-proportional "
                                                                      "noise"),
        K("drift_mm_per_h", T::kNumbers).Unit("mm/h").Count(3).Default("[0, 0, 0]")
            .Doc("drift of the readings"),
        K("max_range_m", T::kNumber).Unit("m").Default("30").Doc("range")}});
  return s;
}

}  // namespace

std::string ScenarioFormatNotice() {
  return "format 2 adds `format: 2` under `scenario:`, and `twinbench check` then validates the "
         "file strictly against schemas/scenario.schema.json (a quoted \"834\" is a string, not "
         "a number; a string that reads as a number or true/false must be quoted); add "
         "`format: 2` once the file passes";
}

const std::vector<ScenarioSection>& ScenarioSections() {
  static const std::vector<ScenarioSection> sections = MakeSections();
  return sections;
}

const ScenarioSection& ScenarioSectionNamed(const std::string& name) {
  for (const ScenarioSection& s : ScenarioSections()) {
    if (s.name == name) return s;
  }
  throw std::logic_error("no scenario section '" + name + "'");
}

YamlKeys ScenarioKeyNames(const std::string& name) {
  YamlKeys keys;
  for (const ScenarioKey& k : ScenarioSectionNamed(name).keys) keys.push_back(k.key);
  return keys;
}

const ScenarioKey& ScenarioKeyOf(const std::string& name, const std::string& key) {
  for (const ScenarioKey& k : ScenarioSectionNamed(name).keys) {
    if (k.key == key) return k;
  }
  throw std::logic_error("no key '" + key + "' in scenario section '" + name + "'");
}

}  // namespace twin
