#include "bench/io/scenario.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <filesystem>
#include <cstdio>
#include <map>
#include <mutex>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include "bench/io/model_loader.h"
#include "bench/io/scenario_keys.h"
#include "bench/io/yaml_util.h"
#include "calib/identification/base_calibration.h"
#include "calib/common/errors.h"
#include "sim/effects/effect.h"

namespace twin {
namespace {

using Keys = YamlKeys;

// The allowed keys of each map: the tables of bench/io/scenario_keys.h (one source with the
// JSON Schema of `twinbench schema`).
const Keys kRootKeys = ScenarioKeyNames("root");
const Keys kScenarioKeys = ScenarioKeyNames("scenario");
const Keys kTrackerKeys = ScenarioKeyNames("tracker");
const Keys kSeedsKeys = ScenarioKeyNames("seeds");
const Keys kRobot1Keys = ScenarioKeyNames("robot1");
const Keys kRobot2Keys = ScenarioKeyNames("robot2");
const Keys kTemperatureSensorKeys = ScenarioKeyNames("temperature_sensor");
const Keys kCameraKeys = ScenarioKeyNames("camera");
const Keys kBoardKeys = ScenarioKeyNames("board");
const Keys kTargetKeys = ScenarioKeyNames("intrinsics_target");
const Keys kPoseKeys = ScenarioKeyNames("pose");
const Keys kTipKeys = ScenarioKeyNames("tip");
const Keys kPhysicsKeys = ScenarioKeyNames("physics");
const Keys kEffectKeys = ScenarioKeyNames("effect");  // any other key: a parameter

double MmToM(double mm) { return mm / 1000.0; }  // division: the nearest double to mm/1000

bool IsIdentifier(const std::string& s) {
  const auto alpha = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
  };
  if (s.empty() || !alpha(s[0])) return false;
  return std::all_of(s.begin(), s.end(),
                     [&](char c) { return alpha(c) || (c >= '0' && c <= '9'); });
}

// Where each TwinSpec field was written ("board.square_m" -> "file:31 scenario.board.square_mm"),
// so that a ValidateTwinSpec message, which starts with the field path, points at the line.
class Locations {
 public:
  void Add(const std::string& spec_field, const std::string& where) { map_[spec_field] = where; }

  // The location of `message`'s leading field path, or of its nearest recorded parent
  // ("robots[1].q_initial[2]" -> "robots[1].q_initial" -> "robots[1]"); else `fallback`.
  std::string Of(const std::string& message, const std::string& fallback) const {
    std::string field = message.substr(0, message.find_first_of(" :"));
    while (!field.empty()) {
      const auto it = map_.find(field);
      if (it != map_.end()) return it->second;
      const std::size_t cut = field.back() == ']' ? field.rfind('[') : field.rfind('.');
      if (cut == std::string::npos || cut == 0) break;
      field.erase(cut);
    }
    return fallback;
  }

 private:
  std::map<std::string, std::string> map_;
};

class ScenarioParser {
 public:
  ScenarioParser(const std::string& source, const std::string& base_dir)
      : r_(source), base_dir_(base_dir) {}

  Scenario Parse(const std::string& text) {
    const YAML::Node root = LoadYamlText(text, r_.source());
    out_.format = ScenarioFormatOf(root, r_.source());  // first: a newer file's new keys
    const YamlMap top(r_, YamlField{root, ""}, kRootKeys);
    const YamlMap m(r_, top.Get("scenario"), kScenarioKeys);
    out_.path = r_.source();
    out_.name = r_.String(m.Get("name"));
    if (out_.name.empty()) r_.Fail(m.Get("name"), "expected a non-empty scenario name");
    ParseSeeds(m);
    ParseRobots(m.Get("robots"));
    RefuseTwoRobotKeys(m);
    if (out_.twin.HasCameraAndBoard()) {
      ParseCamera(m.Get("camera"));
      ParseBoard(m.Get("board"));
      if (const auto f = m.Find("intrinsics_target", false)) ParseIntrinsicsTarget(*f);
    }
    if (const auto f = m.Find("tips", false)) ParseTips(*f);
    DefaultTipsOutward();
    if (const auto f = m.Find("physics", false)) ParsePhysics(*f);
    if (const auto f = m.Find("effects", false)) ParseEffects(*f);
    if (const auto f = m.Find("tracker", false)) ParseTracker(*f);
    // Procedure sections: kept as written, parsed by the procedures that own them.
    if (const auto f = m.Find("calibration", false)) out_.calibration = *f;
    if (const auto f = m.Find("handclasp", false)) out_.handclasp = *f;
    if (const auto f = m.Find("acceptance", false)) out_.acceptance = *f;
    if (const auto f = m.Find("tracker_calibration", false)) out_.tracker_calibration = *f;
    if (out_.twin.num_robots == 1) RequireTrackerCalibration(m);
    Validate();
    return out_;
  }

 private:
  void Locate(const std::string& spec_field, const YamlField& f) {
    locations_.Add(spec_field, r_.Where(f));
  }

  // Refuses, at its line, a key the tables allow only with two robots in a one-robot cell
  // (ScenarioKey::only_with_robots: camera, board, intrinsics_target, calibration, handclasp).
  void RefuseTwoRobotKeys(const YamlMap& m) const {
    if (out_.twin.num_robots == kMaxRobots) return;
    for (const ScenarioKey& k : ScenarioSectionNamed("scenario").keys) {
      if (k.only_with_robots != kMaxRobots) continue;
      if (const auto f = m.Find(k.key, false)) {
        r_.Fail(*f, "is not allowed with one robot: a one-robot cell is a laser-tracker cell, "
                    "without camera, board or intrinsics target, and the optical-axis "
                    "calibration and the handclasp need two robots (bench/io/scenario.h)");
      }
    }
  }

  // A one-robot cell runs the laser-tracker procedure only: without tracker_calibration
  // (ScenarioKey::required_with_robots) nothing would run.
  void RequireTrackerCalibration(const YamlMap& m) const {
    if (!m.Find("tracker_calibration", false)) {
      r_.Fail(m.Get("robots"), "lists one robot, and a one-robot cell runs only the laser-"
                               "tracker procedure: add a tracker: and a tracker_calibration: "
                               "section (bench/runs/tracker_run.h), or a second robot with a "
                               "camera: and a board:");
    }
  }

  // `seed: N` drives both the truth and the estimator; `seeds: {truth, estimator}` sets them
  // apart (each optional, default 1); both keys at once are refused.
  void ParseSeeds(const YamlMap& m) {
    const auto one = m.Find("seed", false);
    const auto two = m.Find("seeds", false);
    if (one && two) {
      r_.Fail(*two, "give either seed (both streams) or seeds: {truth, estimator}, not both");
    }
    if (one) out_.seeds.truth = out_.seeds.estimator = r_.Unsigned64(*one);
    if (two) {
      const YamlMap sm(r_, *two, kSeedsKeys);
      if (const auto f = sm.Find("truth", false)) out_.seeds.truth = r_.Unsigned64(*f);
      if (const auto f = sm.Find("estimator", false)) out_.seeds.estimator = r_.Unsigned64(*f);
      if (const auto f = sm.Find("noise", false)) out_.seeds.noise = r_.Unsigned64(*f);
    }
    out_.twin.seed = out_.seeds.truth;
    out_.twin.noise_seed = out_.seeds.noise;
  }

  Transform PoseFrom(const YamlMap& m) const { return ReadPose(r_, m); }
  Transform Pose(const YamlField& f) const { return PoseFrom(YamlMap(r_, f, kPoseKeys)); }

  // The index of the robot named by f (a robot name of this scenario).
  int RobotIndex(const YamlField& f) const {
    const std::string name = r_.String(f);
    const auto it = std::find(out_.robot_names.begin(), out_.robot_names.end(), name);
    if (it == out_.robot_names.end()) {
      r_.Fail(f, "unknown robot '" + name + "' (robots: " + JoinNames(RobotNames()) + ")");
    }
    return static_cast<int>(it - out_.robot_names.begin());
  }

  const std::vector<std::string>& RobotNames() const { return out_.robot_names; }

  std::string ResolvePath(const std::string& file) const {
    std::filesystem::path p(file);
    if (p.is_relative() && !base_dir_.empty()) p = std::filesystem::path(base_dir_) / p;
    return p.lexically_normal().string();
  }

  Installation ParseInstallation(const YamlField& f) const {
    const std::string s = r_.String(f);
    for (Installation i : {Installation::kFloor, Installation::kWall, Installation::kCeiling}) {
      if (s == ToString(i)) return i;
    }
    r_.Fail(f, "expected floor, wall or ceiling, got '" + s + "'");
  }

  // One robot (a laser-tracker cell) or two (with the camera and the board).
  void ParseRobots(const YamlField& f) {
    Locate("robots", f);
    if (!f.node.IsSequence() || f.node.size() < 1 ||
        f.node.size() > static_cast<std::size_t>(kMaxRobots)) {
      r_.Fail(f, "expected a sequence of one robot (a laser-tracker cell) or two (with the "
                 "camera and the board), got " + DescribeNode(f.node));
    }
    out_.twin.num_robots = static_cast<int>(f.node.size());
    out_.robot_names.resize(f.node.size());
    out_.model_paths.resize(f.node.size());
    for (int i = 0; i < out_.twin.num_robots; ++i) {
      ParseRobot(f.Item(static_cast<std::size_t>(i)), i);
    }
  }

  void ParseRobot(const YamlField& f, int i) {
    const std::string spec = "robots[" + std::to_string(i) + "]";
    Locate(spec, f);
    const YamlMap m(r_, f, i == 0 ? kRobot1Keys : kRobot2Keys);
    RobotSpec& robot = out_.twin.robots[i];

    const YamlField name_field = m.Get("name");
    const std::string name = r_.String(name_field);
    if (!IsIdentifier(name)) {
      r_.Fail(name_field, "expected a robot name of letters, digits and '_' not starting "
                          "with a digit, got '" + name + "'");
    }
    if (i > 0 && name == out_.robot_names[0]) {
      r_.Fail(name_field, "robot name '" + name + "' is already used by robots[0]; names "
                          "must be unique");
    }
    out_.robot_names[i] = name;

    const YamlField model_field = m.Get("model");
    const std::string model_text = r_.String(model_field);
    if (model_text.empty()) r_.Fail(model_field, "expected a model file path, got ''");
    out_.model_paths[i] = ResolvePath(model_text);
    ModelLinks links;
    for (auto [key, value] : {std::pair{"base_link", &links.base_link},
                              std::pair{"tip_link", &links.tip_link}}) {
      if (const auto field = m.Find(key, false)) {
        *value = r_.String(*field);
        if (value->empty()) r_.Fail(*field, std::string("expected a URDF link name, got ''"));
      }
    }
    std::vector<std::string> warnings;
    try {
      robot.model = LoadRobotModel(out_.model_paths[i], links, &warnings);
      for (const std::string& w : warnings) out_.warnings.push_back("robot " + name + ": " + w);
    } catch (const InputError& e) {
      r_.Fail(model_field, "cannot load robot model '" + model_text + "' (resolved to " +
                               out_.model_paths[i] + "): " + e.what());
    }
    robot.model.name = name;  // the scenario's name prefixes the robot's parameter names
    Locate(spec + ".model", model_field);

    const YamlField inst = m.Get("installation");
    robot.installation = ParseInstallation(inst);
    Locate(spec + ".installation", inst);

    if (i == 0) {
      if (const auto base = m.Find("base", false)) {
        robot.X_WB = Pose(*base);
        Locate(spec + ".X_WB", *base);
      }
    } else {
      const YamlField rel = m.Get("base_from_robot1");
      robot.X_WB = out_.twin.robots[0].X_WB * Pose(rel);
      Locate(spec + ".X_WB", rel);
    }

    if (const auto sensor = m.Find("temperature_sensor", false)) {
      const YamlMap sm(r_, *sensor, kTemperatureSensorKeys);
      robot.temperature_sensor.present = true;
      if (const auto v = sm.Find("ambient_C", false)) {
        robot.temperature_sensor.ambient_C = r_.Number(*v);
        Locate(spec + ".temperature_sensor.ambient_C", *v);
      }
      if (const auto v = sm.Find("sigma_K", false)) {
        robot.temperature_sensor.sigma_K = r_.Number(*v);
        Locate(spec + ".temperature_sensor.sigma_K", *v);
      }
    }

    const YamlField q = m.Get("initial_joints_deg");
    const int n = robot.model.num_joints();
    const std::vector<double> q_deg = r_.Numbers(q, n);
    Locate(spec + ".q_initial", q);
    robot.q_initial = JointVector::Zero(n);
    for (int j = 0; j < n; ++j) {
      robot.q_initial(j) = DegToRad(q_deg[static_cast<std::size_t>(j)]);
      Locate(spec + ".q_initial[" + std::to_string(j) + "]", q.Item(static_cast<std::size_t>(j)));
    }
  }

  void ParseCamera(const YamlField& f) {
    Locate("camera", f);
    const YamlMap m(r_, f, kCameraKeys);
    CameraSpec& cam = out_.twin.camera;
    const auto number = [&](const char* key, const char* spec_field, double* value) {
      const YamlField v = m.Get(key);
      *value = r_.Number(v);
      Locate(spec_field, v);
    };

    const YamlField robot = m.Get("robot");
    cam.robot = RobotIndex(robot);
    Locate("camera.robot", robot);
    const YamlField hand_eye = m.Get("hand_eye");
    cam.X_FC = Pose(hand_eye);
    Locate("camera.X_FC", hand_eye);

    const YamlField res = m.Get("resolution");
    const std::vector<int> wh = r_.Integers(res, 2);
    cam.intrinsics.width = wh[0];
    cam.intrinsics.height = wh[1];
    Locate("camera.intrinsics.width", res.Item(0));
    Locate("camera.intrinsics.height", res.Item(1));
    number("fx", "camera.intrinsics.fx", &cam.intrinsics.fx);
    number("fy", "camera.intrinsics.fy", &cam.intrinsics.fy);
    number("cx", "camera.intrinsics.cx", &cam.intrinsics.cx);
    number("cy", "camera.intrinsics.cy", &cam.intrinsics.cy);

    if (const auto d = m.Find("distortion", false)) {
      const std::vector<double> k = r_.Numbers(*d, 5);
      cam.distortion = Distortion{k[0], k[1], k[2], k[3], k[4]};
      const char* names[] = {"k1", "k2", "p1", "p2", "k3"};
      for (std::size_t n = 0; n < 5; ++n) {
        Locate(std::string("camera.distortion.") + names[n], d->Item(n));
      }
    }
    if (const auto v = m.Find("msaa", false)) {
      cam.msaa_samples = r_.Integer(*v);
      Locate("camera.msaa_samples", *v);
    }
    if (const auto v = m.Find("skybox", false)) {
      cam.skybox = r_.Bool(*v);
      Locate("camera.skybox", *v);
    }
    if (const auto v = m.Find("near_mm", false)) {
      cam.near_m = MmToM(r_.Number(*v));
      Locate("camera.near_m", *v);
    }
    if (const auto v = m.Find("far_mm", false)) {
      cam.far_m = MmToM(r_.Number(*v));
      Locate("camera.far_m", *v);
    }
  }

  void ParseBoard(const YamlField& f) {
    Locate("board", f);
    const YamlMap m(r_, f, kBoardKeys);
    BoardSpec& b = out_.twin.board;
    const YamlField robot = m.Get("robot");
    b.robot = RobotIndex(robot);
    Locate("board.robot", robot);
    ParsePlate(m, "board", &b);
    const YamlField mount = m.Get("mount");
    b.X_FT = Pose(mount);
    Locate("board.X_FT", mount);
  }

  // The larger chessboard for the intrinsics step, mounted on the board's bracket in its place
  // (twin side: what the cell has; the calibration section says what the estimator is told).
  // Its mount defaults to the board's.
  void ParseIntrinsicsTarget(const YamlField& f) {
    Locate("intrinsics_target", f);
    const YamlMap m(r_, f, kTargetKeys);
    BoardSpec t;
    t.robot = out_.twin.board.robot;
    t.mass_kg = out_.twin.board.mass_kg;
    t.X_FT = out_.twin.board.X_FT;
    ParsePlate(m, "intrinsics_target", &t);
    if (const auto mount = m.Find("mount", false)) {
      t.X_FT = Pose(*mount);
      Locate("intrinsics_target.X_FT", *mount);
    }
    out_.twin.intrinsics_target = t;
  }

  // The printed plate of a board or target: squares, square_mm (required), margin, thickness
  // and mass (optional); spec fields located under `field`.
  void ParsePlate(const YamlMap& m, const std::string& field, BoardSpec* b) {
    const YamlField squares = m.Get("squares");
    const std::vector<int> n = r_.Integers(squares, 2);
    b->squares_x = n[0];
    b->squares_y = n[1];
    Locate(field + ".squares_x", squares.Item(0));
    Locate(field + ".squares_y", squares.Item(1));
    const YamlField square = m.Get("square_mm");
    b->square_m = MmToM(r_.Number(square));
    Locate(field + ".square_m", square);
    if (const auto v = m.Find("margin_mm", false)) {
      b->margin_m = MmToM(r_.Number(*v));
      Locate(field + ".margin_m", *v);
    }
    if (const auto v = m.Find("thickness_mm", false)) {
      b->thickness_m = MmToM(r_.Number(*v));
      Locate(field + ".thickness_m", *v);
    }
    if (const auto v = m.Find("mass_kg", false)) {
      b->mass_kg = r_.Number(*v);
      Locate(field + ".mass_kg", *v);
    }
  }

  // The laser tracker (truth): sim/world/twin_spec.h, TrackerSpec.
  void ParseTracker(const YamlField& f) {
    Locate("tracker", f);
    const YamlMap m(r_, f, kTrackerKeys);
    TrackerSpec& t = out_.twin.tracker;
    t.present = true;
    const YamlField robot = m.Get("robot");
    t.robot = RobotIndex(robot);
    Locate("tracker.robot", robot);
    const YamlField pose = m.Get("pose");
    t.X_WT = Pose(pose);
    Locate("tracker.X_WT", pose);
    const YamlField reflector = m.Get("reflector_mm");
    const std::vector<double> p = r_.Numbers(reflector, 3);
    t.p_FR = Vector3(MmToM(p[0]), MmToM(p[1]), MmToM(p[2]));
    Locate("tracker.reflector", reflector);
    if (const auto v = m.Find("sigma_mm", false)) {
      t.sigma_m = MmToM(r_.Number(*v));
      Locate("tracker.sigma", *v);
    }
    if (const auto v = m.Find("sigma_um_per_m", false)) {
      t.sigma_per_m = r_.Number(*v) * 1e-6;
      Locate("tracker.sigma_per_m", *v);
    }
    if (const auto v = m.Find("drift_mm_per_h", false)) {
      const std::vector<double> d = r_.Numbers(*v, 3);
      t.drift_m_per_s = Vector3(d[0], d[1], d[2]) * 1e-3 / 3600.0;
      Locate("tracker.drift", *v);
    }
    if (const auto v = m.Find("max_range_m", false)) {
      t.max_range_m = r_.Number(*v);
      Locate("tracker.max_range", *v);
    }
  }

  // A tip without a pose of its own sits at the flange's centre, its capsule behind the point
  // inside the wrist: along -z of L_N where the last link's d is >= 0 (z points out of the
  // face), along +z where d < 0 (URDFs whose last axis points into the wrist, as KUKA's: there
  // the default frame is turned by 180 deg about x, or the capsule would stand out of the
  // flange through whatever is mounted on it).
  void DefaultTipsOutward() {
    for (int i = 0; i < out_.twin.num_robots; ++i) {
      if (tip_pose_given_[i]) continue;
      const KinematicModel& model = out_.twin.robots[i].model;
      if (model.num_joints() < 1 || model.flange().dh.d >= 0.0) continue;
      out_.twin.tips[i].X_FTip.linear() =
          Eigen::AngleAxisd(kPi, Vector3::UnitX()).toRotationMatrix();
    }
  }

  void ParseTips(const YamlField& f) {
    Locate("tips", f);
    const YamlMap m(r_, f, RobotNames());  // keys are robot names
    for (int i = 0; i < out_.twin.num_robots; ++i) {
      const auto entry = m.Find(out_.robot_names[i], false);
      if (!entry) continue;
      const std::string spec = "tips[" + std::to_string(i) + "]";
      Locate(spec, *entry);
      const YamlMap t(r_, *entry, kTipKeys);
      TipSpec& tip = out_.twin.tips[i];
      if (t.Has("xyz_mm") || t.Has("rpy_deg") || t.Has("zyz_deg")) {
        tip.X_FTip = PoseFrom(t);
        tip_pose_given_[i] = true;
        Locate(spec + ".X_FTip", *entry);
      }
      if (const auto v = t.Find("length_mm", false)) {
        tip.length_m = MmToM(r_.Number(*v));
        Locate(spec + ".length_m", *v);
      }
      if (const auto v = t.Find("radius_mm", false)) {
        tip.radius_m = MmToM(r_.Number(*v));
        Locate(spec + ".radius_m", *v);
      }
    }
  }

  void ParsePhysics(const YamlField& f) {
    Locate("physics", f);
    const YamlMap m(r_, f, kPhysicsKeys);
    PhysicsSpec& p = out_.twin.physics;
    // key in the file, field in PhysicsSpec, factor to SI
    struct NumberKey {
      const char* key;
      const char* spec_field;
      double PhysicsSpec::*member;
      double to_si;
    };
    const NumberKey numbers[] = {
        {"timestep_s", "physics.timestep_s", &PhysicsSpec::timestep_s, 1.0},
        {"stiffness_Nm_per_rad", "physics.stiffness", &PhysicsSpec::stiffness, 1.0},
        {"armature_kgm2", "physics.armature", &PhysicsSpec::armature, 1.0},
        {"max_joint_speed_deg_s", "physics.max_joint_speed", &PhysicsSpec::max_joint_speed,
         DegToRad(1.0)},
        {"settle_speed_deg_s", "physics.settle_speed", &PhysicsSpec::settle_speed,
         DegToRad(1.0)},
    };
    for (const NumberKey& k : numbers) {
      if (const auto v = m.Find(k.key, false)) {
        p.*k.member = r_.Number(*v) * k.to_si;
        Locate(k.spec_field, *v);
      }
    }
    if (const auto v = m.Find("settle_steps", false)) {
      p.settle_steps = r_.Integer(*v);
      Locate("physics.settle_steps", *v);
    }
    if (const auto v = m.Find("max_steps", false)) {
      p.max_steps = r_.Integer(*v);
      Locate("physics.max_steps", *v);
    }
    if (const auto v = m.Find("gravity", false)) p.gravity = r_.Bool(*v);
  }

  void ParseEffects(const YamlField& f) {
    Locate("effects", f);
    if (!f.node.IsSequence()) {
      r_.Fail(f, "expected a sequence of effects, got " + DescribeNode(f.node));
    }
    for (std::size_t k = 0; k < f.node.size(); ++k) {
      const YamlField item = f.Item(k);
      const std::string spec = "effects[" + std::to_string(k) + "]";
      Locate(spec, item);
      const YamlMap m(r_, item, kEffectKeys, YamlMap::Extra::kAccept);
      EffectSpec e;
      e.where = r_.Where(item);
      e.type = r_.String(m.Get("type"));
      if (const auto v = m.Find("declared", false)) e.declared = r_.Bool(*v);
      if (const auto v = m.Find("robot", false)) {
        e.robot = RobotIndex(*v);
        Locate(spec + ".robot", *v);
      }
      if (const auto v = m.Find("joint", false)) {
        const int joint = r_.Integer(*v);
        // The joint must exist on every robot the effect acts on (robots come first).
        int joints = kMaxJoints;
        for (int r = 0; r < out_.twin.num_robots; ++r) {
          if (e.robot == -1 || e.robot == r) {
            joints = std::min(joints, out_.twin.robots[r].model.num_joints());
          }
        }
        if (joint < 1 || joint > joints) {
          r_.Fail(*v, "expected a joint number from 1 to " + std::to_string(joints) +
                          ", got " + std::to_string(joint));
        }
        e.joint = joint - 1;
        Locate(spec + ".joint", *v);
      }
      for (const auto& [key, value] : m.extra()) {
        e.params[key] = r_.Number(value);
        Locate(spec + ".params." + key, value);
      }
      out_.twin.effects.push_back(std::move(e));
    }
  }

  // ValidateTwinSpec, its message re-thrown at the line of the offending key; then each
  // effect is built once, so an unknown type or parameter is refused before anything runs.
  void Validate() const {
    try {
      ValidateTwinSpec(out_.twin, r_.source());
    } catch (const InputError& e) {
      throw InputError(locations_.Of(e.message(), r_.source()), e.message());
    }
    MakeEffects(out_.twin);
  }

  YamlReader r_;
  std::string base_dir_;
  Locations locations_;
  Scenario out_;
  std::array<bool, kMaxRobots> tip_pose_given_{};  // tips.<robot> gave xyz_mm or a rotation
};

}  // namespace

void PrintFormatNotice(const std::string& path, int format) {
  // Once per file and process: a study loads its scenario once per trial.
  static std::mutex mutex;
  static std::set<std::string> noticed;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!noticed.insert(path).second) return;
  std::fprintf(stderr, "notice: %s: scenario format %d (no scenario.format); %s\n", path.c_str(),
               format, ScenarioFormatNotice().c_str());
}

int ScenarioFormatOf(const YAML::Node& root, const std::string& source) {
  if (!root.IsMap() || !root["scenario"].IsMap() || !root["scenario"]["format"]) return 1;
  const YamlReader r(source);
  const YamlField f{root["scenario"]["format"], "scenario.format"};
  const int format = r.Integer(f);
  if (format < 1) {
    r.Fail(f, "expected a scenario format version >= 1, got " + std::to_string(format));
  }
  if (format > kScenarioFormat) {
    r.Fail(f, "scenario format " + std::to_string(format) + " is newer than this twinbench "
              "knows (newest: " + std::to_string(kScenarioFormat) + "); use a newer twinbench");
  }
  return format;
}

Scenario ParseScenario(const std::string& text, const std::string& source,
                       const std::string& base_dir) {
  return ScenarioParser(source, base_dir).Parse(text);
}

Scenario LoadScenario(const std::string& path) {
  const std::string text = ReadTextFile(path);
  Scenario scenario =
      ParseScenario(text, path, std::filesystem::path(path).parent_path().string());
  PrintWarnings(scenario.warnings);
  if (scenario.format < kScenarioFormat) PrintFormatNotice(path, scenario.format);
  return scenario;
}

void RequireTwoRobots(const Scenario& scenario, const std::string& section,
                      const std::string& what) {
  if (scenario.twin.HasCameraAndBoard()) return;
  throw InputError(scenario.path + " scenario." + section,
                   what + " needs two robots; this scenario's cell has one (a laser-tracker "
                   "cell: tracker_calibration)");
}

void ApplyTrial(int trial, Scenario* scenario) {
  if (trial < 0) {
    throw InputError("--trial", std::to_string(trial) + ": expected a trial number >= 0");
  }
  const auto t = static_cast<std::uint64_t>(trial) - static_cast<std::uint64_t>(scenario->trial);
  scenario->seeds.truth += t;
  scenario->seeds.estimator += t;
  if (scenario->seeds.noise) *scenario->seeds.noise += t;
  scenario->twin.seed = scenario->seeds.truth;
  scenario->twin.noise_seed = scenario->seeds.noise;
  scenario->trial = trial;
}

}  // namespace twin
