#include "bench/io/calibration_config.h"

#include <algorithm>
#include <string>

#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

const YamlKeys kKeys = {"robots",           "rough_base_from_robot1", "rough_hand_eye",
                        "board_mount",      "intrinsics_views",       "planning",
                        "servo",            "calibration_axes",       "scoring",
                        "calibration_split", "refit_all_axes"};
const YamlKeys kPoseKeys = {"xyz_mm", "rpy_deg", "zyz_deg"};
const YamlKeys kPlanningKeys = {"axes",
                                "positions_per_axis",
                                "swarm_size",
                                "iterations",
                                "runs",
                                "distance_step_mm",
                                "planning_max_distance_mm",
                                "min_distance_mm",
                                "max_distance_mm",
                                "min_joint_limit_distance_deg",
                                "min_singular_value",
                                "max_visibility_angle_deg",
                                "camera_reach_mm",
                                "camera_height_mm",
                                "seed"};
const YamlKeys kServoKeys = {"tolerance_px", "max_iterations", "gain"};
const YamlKeys kScoringKeys = {"configurations", "seed"};

}  // namespace

CalibrationConfig ParseCalibrationConfig(const Scenario& sc) {
  const YamlReader r(sc.path);
  if (!IsPresent(sc.calibration)) {
    throw InputError(sc.path + " scenario.calibration",
                     "missing: `twinbench run` needs a calibration section (see "
                     "scenarios/paper_reinovo.yaml)");
  }
  const YamlMap m(r, sc.calibration, kKeys);
  CalibrationConfig c;
  for (int k = 0; k < 2; ++k) c.knowledge.nominal[k] = sc.twin.robots[k].model;
  const auto pose = [&](const YamlField& f) { return ReadPose(r, YamlMap(r, f, kPoseKeys)); };
  c.knowledge.X_B1B2 = pose(m.Get("rough_base_from_robot1"));
  c.knowledge.X_FC = pose(m.Get("rough_hand_eye"));
  c.knowledge.X_FT = sc.twin.board.X_FT;
  if (const auto f = m.Find("board_mount", false)) c.knowledge.X_FT = pose(*f);
  c.knowledge.board =
      BoardGeometry{sc.twin.board.squares_x, sc.twin.board.squares_y, sc.twin.board.square_m};

  OpticalAxisOptions& o = c.options;
  // The estimator's own randomness follows the scenario's estimator seed (+ trial); a
  // planning.seed pins the PSO for every trial (one plan per study, see PlanStore).
  o.seed = sc.seeds.estimator;
  o.servo.ik_seed = sc.seeds.estimator;
  o.planner.seed = sc.seeds.estimator;
  o.robots = {sc.twin.board.robot, sc.twin.camera.robot};
  if (const auto f = m.Find("robots", false)) {
    if (!f->node.IsSequence() || f->node.size() < 1 || f->node.size() > 2) {
      r.Fail(*f, "expected a list of one or two robot names, got " + DescribeNode(f->node));
    }
    o.robots.clear();
    for (std::size_t i = 0; i < f->node.size(); ++i) {
      const YamlField item = f->Item(i);
      const std::string name = r.String(item);
      const auto it = std::find(sc.robot_names.begin(), sc.robot_names.end(), name);
      if (it == sc.robot_names.end()) {
        r.Fail(item, "unknown robot '" + name + "' (robots: " + sc.robot_names[0] + ", " +
                         sc.robot_names[1] + ")");
      }
      const int index = static_cast<int>(it - sc.robot_names.begin());
      if (std::find(o.robots.begin(), o.robots.end(), index) != o.robots.end()) {
        r.Fail(item, "robot '" + name + "' listed twice");
      }
      o.robots.push_back(index);
    }
  }
  if (const auto f = m.Find("intrinsics_views", false)) o.intrinsics_views = r.Integer(*f);
  PosePlannerOptions& p = o.planner;
  if (const auto f = m.Find("planning", false)) {
    const YamlMap pm(r, *f, kPlanningKeys);
    const auto integer = [&](const char* key, int* v) {
      if (const auto g = pm.Find(key, false)) *v = r.Integer(*g);
    };
    const auto number = [&](const char* key, double scale, double* v) {
      if (const auto g = pm.Find(key, false)) *v = r.Number(*g) * scale;
    };
    integer("axes", &p.num_axes);
    integer("positions_per_axis", &p.positions_per_axis);
    integer("swarm_size", &p.swarm_size);
    integer("iterations", &p.iterations);
    integer("runs", &p.runs);
    number("distance_step_mm", 1e-3, &p.distance_step);
    number("planning_max_distance_mm", 1e-3, &p.planning_max_distance);
    number("min_distance_mm", 1e-3, &p.min_distance);
    number("max_distance_mm", 1e-3, &p.max_distance);
    number("min_joint_limit_distance_deg", DegToRad(1.0), &p.min_joint_limit_distance);
    number("min_singular_value", 1.0, &p.min_singular_value);
    number("max_visibility_angle_deg", DegToRad(1.0), &p.max_visibility_angle);
    number("camera_reach_mm", 1e-3, &p.camera_reach);
    number("camera_height_mm", 1e-3, &p.camera_height);
    if (const auto g = pm.Find("seed", false)) p.seed = r.Unsigned64(*g);
  }
  if (const auto f = m.Find("servo", false)) {
    const YamlMap sm(r, *f, kServoKeys);
    if (const auto g = sm.Find("tolerance_px", false)) o.servo.tolerance_px = r.Number(*g);
    if (const auto g = sm.Find("max_iterations", false)) o.servo.max_iterations = r.Integer(*g);
    if (const auto g = sm.Find("gain", false)) o.servo.gain = r.Number(*g);
  }
  o.calibration_axes = std::min(3, p.num_axes);
  if (const auto f = m.Find("calibration_axes", false)) o.calibration_axes = r.Integer(*f);
  if (const auto f = m.Find("refit_all_axes", false)) o.refit_all_axes = r.Bool(*f);
  if (const auto f = m.Find("calibration_split", false)) {
    const std::string v = r.String(*f);
    if (v == "best_conditioned") {
      o.split = OpticalAxisOptions::Split::kBestConditioned;
    } else if (v == "first") {
      o.split = OpticalAxisOptions::Split::kFirst;
    } else {
      r.Fail(*f, "must be best_conditioned or first, got '" + v + "'");
    }
  }
  if (const auto f = m.Find("scoring", false)) {
    const YamlMap sm(r, *f, kScoringKeys);
    if (const auto g = sm.Find("configurations", false)) {
      c.scoring_configurations = r.Integer(*g);
      if (c.scoring_configurations < 10) {
        r.Fail(*g, "expected at least 10 configurations, got " +
                       std::to_string(c.scoring_configurations));
      }
    }
    if (const auto g = sm.Find("seed", false)) c.scoring_seed = r.Unsigned64(*g);
  }
  try {
    ValidateOpticalAxisOptions(o);
  } catch (const InputError& e) {
    r.Fail(sc.calibration, std::string(e.what()) + " (" + e.where() + ")");
  }
  return c;
}

}  // namespace twin
