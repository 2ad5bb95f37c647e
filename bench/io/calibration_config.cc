#include "bench/io/calibration_config.h"

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "bench/io/scenario_keys.h"
#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

// The keys of the section and its maps: their tables in bench/io/scenario_keys.cc (the
// scenario schema's source), which restate the limits checked below.
const YamlKeys kKeys = ScenarioKeyNames("calibration");
const YamlKeys kTargetKeys = ScenarioKeyNames("calibration_target");
const YamlKeys kPlanningKeys = ScenarioKeyNames("calibration_planning");
const YamlKeys kServoKeys = ScenarioKeyNames("calibration_servo");
const YamlKeys kScoringKeys = ScenarioKeyNames("calibration_scoring");

// Plausibility limits of the told values: the same as the twin's (sim/world/twin_spec.cc).
constexpr double kMaxToldBaseDistanceM = 20.0;
constexpr double kMaxToldToolOffsetM = 1.0;
// Largest PSO effort: 20 times the paper's 10 particles x 100 iterations x 5 runs.
constexpr double kMaxPlanningEvaluations = 1e5;

std::string DescribeNumber(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// A whole number in [lo, hi]; `why` is the limit's reason.
int BoundedInteger(const YamlReader& r, const YamlField& f, int lo, int hi, const char* why) {
  const int v = r.Integer(f);
  if (v < lo || v > hi) {
    r.Fail(f, "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) +
                  " (" + why + "), got " + std::to_string(v));
  }
  return v;
}

// A number in [lo, hi] in the key's unit; `why` is the limit's reason.
double BoundedNumber(const YamlReader& r, const YamlField& f, double lo, double hi,
                     const char* why) {
  const double v = r.Number(f);
  if (v < lo || v > hi) {
    r.Fail(f, "expected a number in [" + DescribeNumber(lo) + ", " + DescribeNumber(hi) + "] (" +
                  why + "), got " + DescribeNumber(v));
  }
  return v;
}

// A printed chessboard by drawing: its squares (even counts, so that a centre inner corner
// exists) and the printed square side [mm].
BoardGeometry ReadPlate(const YamlReader& r, const YamlField& squares, const YamlField& square) {
  const std::vector<int> n = r.Integers(squares, 2);
  for (std::size_t k = 0; k < 2; ++k) {
    if (n[k] < 2 || n[k] > 30 || n[k] % 2 != 0) {
      r.Fail(squares.Item(k), "expected an even number of squares from 2 to 30 (the feature "
                              "point is the centre inner corner; larger patterns are beyond "
                              "any flange-mounted target), got " + std::to_string(n[k]));
    }
  }
  const double mm = r.Number(square);
  if (!(mm >= 1.0 && mm <= 500.0)) {
    r.Fail(square, "expected a square side in [1, 500] mm (a printed square of a flange-"
                   "mounted board), got " + DescribeNode(square.node));
  }
  return BoardGeometry{n[0], n[1], mm / 1000.0};
}

}  // namespace

CalibrationConfig ParseCalibrationConfig(const Scenario& sc) {
  const YamlReader r(sc.path);
  if (!IsPresent(sc.calibration)) {
    throw InputError(sc.path + " scenario.calibration",
                     "missing: `twinbench run` needs a calibration section (see "
                     "scenarios/paper_reinovo.yaml)");
  }
  RequireTwoRobots(sc, "calibration", "the optical-axis calibration");
  const YamlMap m(r, sc.calibration, kKeys);
  CalibrationConfig c;
  // What the estimator is told comes from this section only, never from the twin's truth
  // (scenario.robots[1].base_from_robot1, camera.hand_eye, board.*): the nominal models are
  // the model files (the twin perturbs them by its geometry effects).
  for (int k = 0; k < 2; ++k) c.knowledge.nominal[k] = sc.twin.robots[k].model;
  c.knowledge.X_B1B2 = ReadPoseWithin(r, m.Get("rough_base_from_robot1"), kMaxToldBaseDistanceM,
                                    "two arms that see each other stand within a few metres");
  c.knowledge.X_FC = ReadPoseWithin(r, m.Get("rough_hand_eye"), kMaxToldToolOffsetM,
                                  "a flange tool's bracket is shorter than a metre");
  c.knowledge.X_FT = ReadPoseWithin(r, m.Get("board_mount"), kMaxToldToolOffsetM,
                                  "a flange tool's bracket is shorter than a metre");
  c.knowledge.board = ReadPlate(r, m.Get("board_squares"), m.Get("board_square_mm"));
  if (const auto f = m.Find("intrinsics_target", false)) {
    const YamlMap t(r, *f, kTargetKeys);
    c.knowledge.intrinsics_target = ReadPlate(r, t.Get("squares"), t.Get("square_mm"));
  }
  if (const auto f = m.Find("board_mass_kg", false)) {
    c.board_mass_kg = r.Number(*f);
    // A flange-mounted target with its bracket: above 50 kg it is no board a small arm holds.
    if (!(c.board_mass_kg >= 0.0 && c.board_mass_kg <= 50.0)) {
      r.Fail(*f, "expected 0 to 50 kg (the board with its bracket, as weighed)");
    }
  }

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
        r.Fail(item, "unknown robot '" + name + "' (robots: " + JoinNames(sc.robot_names) + ")");
      }
      const int index = static_cast<int>(it - sc.robot_names.begin());
      if (std::find(o.robots.begin(), o.robots.end(), index) != o.robots.end()) {
        r.Fail(item, "robot '" + name + "' listed twice");
      }
      o.robots.push_back(index);
    }
  }
  if (const auto f = m.Find("intrinsics_views", false)) {
    o.intrinsics_views = BoundedInteger(r, *f, 3, 500, "Zhang's method needs 3 views; 500 "
                                                       "rendered views are minutes of frames");
  }
  if (const auto f = m.Find("intrinsics_distortion", false)) {
    const std::string v = r.String(*f);
    if (v == "brown") {
      o.intrinsics.fix_all_distortion = false;
    } else if (v == "none") {
      o.intrinsics.fix_all_distortion = true;
    } else {
      r.Fail(*f, "must be brown (k1, k2, p1, p2 estimated) or none (pinhole), got '" + v + "'");
    }
  }
  PosePlannerOptions& p = o.planner;
  if (const auto f = m.Find("planning", false)) {
    const YamlMap pm(r, *f, kPlanningKeys);
    // Plausibility limits, each with its reason; together they bound the planning's time
    // (evaluations = swarm x iterations x runs, each a few IK solutions).
    const auto integer = [&](const char* key, int lo, int hi, const char* why, int* v) {
      if (const auto g = pm.Find(key, false)) *v = BoundedInteger(r, *g, lo, hi, why);
    };
    const auto number = [&](const char* key, double scale, double lo, double hi,
                            const char* why, double* v) {
      if (const auto g = pm.Find(key, false)) *v = BoundedNumber(r, *g, lo, hi, why) * scale;
    };
    integer("axes", 1, 20, "the paper plans 5; 20 axes is hours of servoing", &p.num_axes);
    integer("positions_per_axis", 3, 100, "a line needs 3 points; the paper takes 10",
            &p.positions_per_axis);
    integer("swarm_size", 1, 1000, "the paper's swarm is 10", &p.swarm_size);
    integer("iterations", 1, 10000, "the paper iterates 100 times", &p.iterations);
    integer("runs", 1, 100, "the paper runs 5 times", &p.runs);
    const double evaluations = double(p.swarm_size) * p.iterations * p.runs;
    if (evaluations > kMaxPlanningEvaluations) {
      r.Fail(*f, "swarm_size x iterations x runs = " + DescribeNumber(evaluations) +
                     " fitness evaluations; at most " + DescribeNumber(kMaxPlanningEvaluations) +
                     " (20 times the paper's 5000, already minutes of planning)");
    }
    const char* distance = "camera-board distances of a hand camera are below 5 m";
    number("distance_step_mm", 1e-3, 0.1, 5000, distance, &p.distance_step);
    number("planning_max_distance_mm", 1e-3, 1, 5000, distance, &p.planning_max_distance);
    number("min_distance_mm", 1e-3, 0, 5000, distance, &p.min_distance);
    number("max_distance_mm", 1e-3, 1, 5000, distance, &p.max_distance);
    number("min_joint_limit_distance_deg", DegToRad(1.0), 0, 90,
           "a margin of more than 90 deg to every limit leaves no pose", &p.min_joint_limit_distance);
    number("min_singular_value", 1.0, 0, 10,
           "manipulator singular values of arms this size are below 2", &p.min_singular_value);
    number("max_visibility_angle_deg", DegToRad(1.0), 0.1, 89,
           "a board seen at 90 deg or more is seen edge-on or from behind",
           &p.max_visibility_angle);
    const char* reach = "the camera region lies within the cell, a few metres";
    number("camera_reach_mm", 1e-3, -5000, 5000, reach, &p.camera_reach);
    number("camera_height_mm", 1e-3, -5000, 5000, reach, &p.camera_height);
    if (const auto g = pm.Find("seed", false)) p.seed = r.Unsigned64(*g);
    if (const auto g = pm.Find("select_run", false)) {
      const std::string v = r.String(*g);
      if (v == "best_fitness") {
        p.select_run = PosePlannerOptions::RunSelection::kBestFitness;
      } else if (v == "predicted_error") {
        p.select_run = PosePlannerOptions::RunSelection::kPredictedError;
      } else {
        r.Fail(*g, "must be best_fitness (the paper's 1/O1) or predicted_error, got '" + v + "'");
      }
    }
    if (const auto g = pm.Find("ik_seed", false)) {
      const std::string v = r.String(*g);
      if (v != "mid_range" && v != "start_pose") {
        r.Fail(*g, "must be mid_range (the joint limits' middle) or start_pose (the set-up "
                   "pose), got '" + v + "'");
      }
      o.plan_from_start_pose = v == "start_pose";
    }
    if (const auto g = pm.Find("ik", false)) {
      const std::string v = r.String(*g);
      if (v != "iterative" && v != "closed_form") {
        r.Fail(*g, "must be iterative (damped least squares) or closed_form (an arm with a "
                   "spherical wrist), got '" + v + "'");
      }
      p.closed_form_ik = v == "closed_form";
    }
  }
  if (const auto f = m.Find("servo", false)) {
    const YamlMap sm(r, *f, kServoKeys);
    if (const auto g = sm.Find("tolerance_px", false)) {
      o.servo.tolerance_px = BoundedNumber(r, *g, 1e-3, 100, "the detector's corners are good to "
                                           "~0.05 px; 100 px is no alignment");
    }
    if (const auto g = sm.Find("max_iterations", false)) {
      o.servo.max_iterations = BoundedInteger(r, *g, 1, 1000, "the servo converges in a few "
                                              "iterations; each is a frame and a move");
    }
    if (const auto g = sm.Find("gain", false)) {
      o.servo.gain = BoundedNumber(r, *g, 0.01, 2.0, "a gain above 2 makes the servo diverge");
    }
    if (const auto g = sm.Find("encoder_readings", false)) {
      o.servo.encoder_readings = BoundedInteger(r, *g, 1, 10000, "readings averaged at each "
                                                "aligned pose; beyond 10000 a controller's "
                                                "cycles add minutes to a calibration");
    }
  }
  o.calibration_axes = std::min(3, p.num_axes);
  if (const auto f = m.Find("calibration_axes", false)) o.calibration_axes = r.Integer(*f);
  if (const auto f = m.Find("refit_all_axes", false)) o.refit_all_axes = r.Bool(*f);
  if (const auto f = m.Find("board_pose_test_p", false)) {
    o.board_pose_test_p = BoundedNumber(r, *f, 0.0, 0.5, "a p-value; 0 turns the board pose's "
                                        "test off, and above 0.5 it would refuse most poses");
  }
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
      if (c.scoring_configurations < 10 || c.scoring_configurations > 100000) {
        r.Fail(*g, "expected 10 to 100000 configurations (the scoring's time grows with them), "
                   "got " + std::to_string(c.scoring_configurations));
      }
    }
    if (const auto g = sm.Find("seed", false)) c.scoring_seed = r.Unsigned64(*g);
  }
  c.discovery.seed = sc.seeds.estimator;
  if (const auto f = m.Find("diagnosis", false)) {
    ParseDiagnosisSection(r, *f, sc.twin.robots[0].model, &c.diagnosis, &c.discovery, true);
  }
  try {
    ValidateOpticalAxisOptions(o);
  } catch (const InputError& e) {
    r.Fail(sc.calibration, std::string(e.what()) + " (" + e.where() + ")");
  }
  return c;
}

}  // namespace twin
