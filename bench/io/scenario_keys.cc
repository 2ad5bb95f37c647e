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

// A printed chessboard by drawing, as the calibration reads it (ReadPlate): even square counts
// from 2 to 30 and a square side in [1, 500] mm.
std::vector<ScenarioKey> DrawnPlateKeys(const std::string& squares, const std::string& side) {
  return {
      K(squares, T::kIntegers).Required().Count(2).Min(2).Max(30).MultipleOf(2)
          .Doc("[x, y] squares of the printed board (even counts, so that a centre inner corner "
               "exists)"),
      K(side, T::kNumber).Required().Unit("mm").Min(1).Max(500).Doc("its printed square side"),
  };
}

// The diagnosis: section (bench/io/diagnosis_config.h); the optical axes' also states the
// noise of the diagnosis' floor. Ranges: ParseDiagnosisSection and ValidateDiscoveryOptions.
std::vector<ScenarioKey> DiagnosisKeys(bool optical_axes) {
  std::vector<ScenarioKey> keys = {
      K("enabled", T::kBoolean).Default("true").Doc("false: skip it (as --no-diagnosis)"),
      K("alpha", T::kNumber).Above(0).Below(0.5).Default("0.05")
          .Doc("level of the residual test and family-wise level of each step"),
      K("min_gain_percent", T::kNumber).Unit("%").Min(0).Below(100).Default("5")
          .Doc("smallest held-out gain worth a term"),
      K("max_effects", T::kInteger).Min(0).Max(10).Default("10")
          .Doc("effects added at most (the search ends on its tests first)"),
      K("folds", T::kInteger).Min(2).Max(20).Default("5").Doc("K of the cross-validations"),
      K("truth_poses", T::kInteger).Min(10).Max(10000).Default("60")
          .Doc("poses of the physical-truth scoring of the discovered model (bench)"),
      K("candidates", T::kStrings).Counts(1, 0).Default("every term")
          .Doc("terms TYPE[:JOINT[:ORDERS]] (bench/io/term_spec_text.h), checked against the "
               "robot's nominal model")};
  if (optical_axes) {
    keys.push_back(K("perpendicular_sigma_mm", T::kNumber).Unit("mm").Min(1e-4).Max(10)
                       .Default("0.02")
                       .Doc("the camera's measurement of the servo's residual offset"));
    keys.push_back(K("depth_sigma_mm", T::kNumber).Unit("mm").Min(1e-4).Max(10).Default("0.1")
                       .Doc("the depth from the board pose"));
    keys.push_back(K("encoder_sigma_deg", T::kNumber).Unit("deg").Min(0).Max(0.5).Default("0")
                       .Doc("the encoders' stated noise (0: not stated)"));
  }
  keys.push_back(K("screen", T::kBoolean).Default("true")
                     .Doc("fit every candidate on all the data when the residual is consistent "
                          "with the noise"));
  return keys;
}

// The procedure sections: calibration (bench/io/calibration_config.cc), handclasp
// (bench/runs/handclasp_run.cc), tracker_calibration (bench/runs/tracker_run.cc), acceptance
// (bench/report/acceptance.cc), with their nested maps. Each range restates its parser's check.
// function-length: table
void AddProcedureSections(std::vector<ScenarioSection>* out) {
  std::vector<ScenarioSection>& s = *out;
  {
    std::vector<ScenarioKey> keys = {
        K("robots", T::kStrings).Counts(1, 2).Default("the board robot, then the camera robot")
            .Doc("the passive robots to calibrate, in order, by name (each once)"),
        K("rough_base_from_robot1", T::kSection).Required().Of("pose")
            .Doc("told X_B1B2, as drawn (translation within 20000 mm)"),
        K("rough_hand_eye", T::kSection).Required().Of("pose")
            .Doc("told X_FC, as drawn (translation within 1000 mm)"),
        K("board_mount", T::kSection).Required().Of("pose")
            .Doc("told X_FT, as drawn (translation within 1000 mm)")};
    for (const ScenarioKey& k : DrawnPlateKeys("board_squares", "board_square_mm")) {
      keys.push_back(k);
    }
    const std::vector<ScenarioKey> rest = {
        K("board_mass_kg", T::kNumber).Unit("kg").Min(0).Max(50).Default("0 (not told)")
            .Doc("the board with its bracket, as weighed, for the diagnosis' gravity terms"),
        K("intrinsics_target", T::kSection).Of("calibration_target").Default("the board")
            .Doc("a larger chessboard by drawing for Zhang's method (the cell must have one: "
                 "scenario.intrinsics_target)"),
        K("intrinsics_views", T::kInteger).Min(3).Max(500).Default("40")
            .Doc("board views for Zhang's method"),
        K("intrinsics_distortion", T::kString).OneOf({"brown", "none"}).Default("brown")
            .Doc("the lens model Zhang's method estimates: brown (k1, k2, p1, p2) or none "
                 "(pinhole)"),
        K("planning", T::kSection).Of("calibration_planning")
            .Doc("pose planning, section IV and eq. 50 (defaults: the paper's)"),
        K("servo", T::kSection).Of("calibration_servo").Doc("the visual servo"),
        K("calibration_axes", T::kInteger).Min(1).Max(20).Default("3, or planning.axes if fewer")
            .Doc("whole axes in the calibration set, 1 to planning.axes; the rest validate"),
        K("calibration_split", T::kString).OneOf({"best_conditioned", "first"})
            .Default("best_conditioned").Doc("which axes form the calibration set"),
        K("refit_all_axes", T::kBoolean).Default("true")
            .Doc("deliver the model refit on all axes after validation"),
        K("board_pose_test_p", T::kNumber).Min(0).Max(0.5).Default("1e-6")
            .Doc("level of the chi-square test of an aligned pose's board pose (0: off)"),
        K("scoring", T::kSection).Of("calibration_scoring").Doc("truth metrics (bench only)"),
        K("diagnosis", T::kSection).Of("calibration_diagnosis")
            .Doc("model discovery per calibrated robot on its aligned poses")};
    keys.insert(keys.end(), rest.begin(), rest.end());
    s.push_back({"calibration", "The optical-axis procedure: what the estimator is told and its "
                                "options (bench/io/calibration_config.h).",
                 keys});
  }
  s.push_back({"calibration_target", "The intrinsics target by drawing (calibration).",
               DrawnPlateKeys("squares", "square_mm")});
  s.push_back(
      {"calibration_planning", "Pose planning by PSO (section IV); swarm_size x iterations x "
                               "runs is at most 1e5 fitness evaluations.",
       {K("axes", T::kInteger).Min(1).Max(20).Default("5").Doc("q, optical axes"),
        K("positions_per_axis", T::kInteger).Min(3).Max(100).Default("10")
            .Doc("p, passive positions per axis"),
        K("swarm_size", T::kInteger).Min(1).Max(1000).Default("10").Doc("PSO particles"),
        K("iterations", T::kInteger).Min(1).Max(10000).Default("100")
            .Doc("PSO iterations per run"),
        K("runs", T::kInteger).Min(1).Max(100).Default("5").Doc("independent PSO runs"),
        K("distance_step_mm", T::kNumber).Unit("mm").Min(0.1).Max(5000).Default("20")
            .Doc("D_step of eq. 38"),
        K("planning_max_distance_mm", T::kNumber).Unit("mm").Min(1).Max(5000).Default("500")
            .Doc("largest planned camera-board distance"),
        K("min_distance_mm", T::kNumber).Unit("mm").Min(0).Max(5000).Default("300")
            .Doc("C4: D_min of eq. 30"),
        K("max_distance_mm", T::kNumber).Unit("mm").Min(1).Max(5000).Default("600")
            .Doc("C5: D_max of eq. 33"),
        K("min_joint_limit_distance_deg", T::kNumber).Unit("deg").Min(0).Max(90).Default("10")
            .Doc("C1: margin to every joint limit"),
        K("min_singular_value", T::kNumber).Min(0).Max(10).Default("0.1")
            .Doc("C2: smallest manipulator singular value"),
        K("max_visibility_angle_deg", T::kNumber).Unit("deg").Min(0.1).Max(89).Default("30")
            .Doc("C3: largest angle between board normal and axis"),
        K("camera_reach_mm", T::kNumber).Unit("mm").Min(-5000).Max(5000).Default("400")
            .Doc("centre of the camera search box, from the active base towards the passive "
                 "base"),
        K("camera_height_mm", T::kNumber).Unit("mm").Min(-5000).Max(5000).Default("400")
            .Doc("... and up"),
        K("seed", T::kUnsigned).Default("the scenario's estimator seed (+ trial)")
            .Doc("PSO seed, the same for every trial of a study (one plan per study)"),
        K("select_run", T::kString).OneOf({"best_fitness", "predicted_error"})
            .Default("best_fitness").Doc("which PSO run's poses"),
        K("ik_seed", T::kString).OneOf({"mid_range", "start_pose"}).Default("mid_range")
            .Doc("where each axis's IK starts: the joint limits' middle or the joints read "
                 "when the procedure starts (arms whose joints turn a full turn or more)"),
        K("ik", T::kString).OneOf({"iterative", "closed_form"}).Default("iterative")
            .Doc("the planner's IK: damped least squares, or the closed form of a spherical "
                 "wrist (other arms: iterative); docs/results/paired_studies.md")}});
  s.push_back(
      {"calibration_servo", "The visual servo's options.",
       {K("tolerance_px", T::kNumber).Unit("px").Min(1e-3).Max(100).Default("0.1")
            .Doc("aligned when the offsets are below this"),
        K("max_iterations", T::kInteger).Min(1).Max(1000).Default("10")
            .Doc("corrective moves before giving up"),
        K("gain", T::kNumber).Min(0.01).Max(2).Default("1")
            .Doc("fraction of the estimated correction applied per move"),
        K("encoder_readings", T::kInteger).Min(1).Max(10000).Default("1")
            .Doc("readings averaged at each aligned pose (at rest)")}});
  s.push_back(
      {"calibration_scoring", "Truth metrics (bench only).",
       {K("configurations", T::kInteger).Min(10).Max(100000).Default("200")
            .Doc("random joint configurations"),
        K("seed", T::kUnsigned).Default("1").Doc("their seed")}});
  s.push_back({"calibration_diagnosis", "Model discovery on the aligned poses of each calibrated "
                                        "robot (bench/io/diagnosis_config.h).",
               DiagnosisKeys(true)});
  s.push_back(
      {"handclasp", "The handclasp base-frame procedure (bench/runs/handclasp_run.h); the "
                    "dual-arm workflow is a calibration: and a handclasp: section together.",
       {K("rough_base_from_robot1", T::kSection).Required().Of("pose")
            .Doc("told X_B1B2, as drawn (translation within 20000 mm)"),
        K("tips", T::kSectionMap).Required().Of("pose")
            .Doc("told X_FTip of each robot by drawing, keyed by robot name (both robots; "
                 "translation within 1000 mm)"),
        K("points", T::kOneOf).Default("auto")
            .Either({K("", T::kString).OneOf({"auto"})
                         .Doc("corners of the largest reachable cube between the shoulders"),
                     K("", T::kNumberLists).Unit("mm").Counts(4, 100).ItemCount(3)
                         .Doc("[x, y, z] contact points in robot 1's base frame (each within "
                              "5000 mm)")})
            .Doc("the taught contact points"),
        K("operator_error_mm", T::kNumber).Unit("mm").Min(0).Max(10).Default("0")
            .Doc("the simulated operator's alignment error, sigma per axis (truth)"),
        K("constraint", T::kString)
            .OneOf({"auto", "general", "floor_floor", "floor_wall", "floor_ceiling"})
            .Default("auto").Doc("the installation constraint (auto: implied by the "
                                 "installations)"),
        K("trials", T::kInteger).Min(1).Max(1000).Default("1")
            .Doc("seeded batch: trial t uses seed + t (1 with a calibration: section)"),
        K("coupled_motion", T::kBoolean).Default("true").Doc("run the coupled-motion check"),
        K("calibrated_operator_error_mm", T::kNumber).Unit("mm").Min(0).Max(10).Default("0.1")
            .Doc("the workflow's second handclasp: operator alignment error, sigma per axis"),
        K("calibrated_tip_identification", T::kBoolean).Default("true")
            .Doc("the workflow's second handclasp identifies both tips with X_B1B2")}});
  s.push_back(
      {"tracker_calibration", "The laser-tracker procedure (bench/runs/tracker_run.h); the "
                              "truth is scenario.tracker.",
       {K("robot", T::kString).Required().Doc("the robot carrying the reflector (the tracker's)"),
        K("told_reflector_mm", T::kNumbers).Required().Unit("mm").Count(3)
            .Doc("the reflector in the flange frame, by drawing (within 500 mm)"),
        K("poses", T::kInteger).Required().Min(1).Max(100000).Doc("measured poses"),
        K("max_attempts", T::kInteger).Min(1).Max(1000000).Default("3 x poses")
            .Doc("configurations tried at most (at least poses)"),
        K("joint_margin_deg", T::kNumber).Unit("deg").Min(0).Max(45).Default("10")
            .Doc("off each joint limit"),
        K("holdout", T::kNumber).Above(0).Max(0.5).Default("0.2")
            .Doc("the part each held-out split keeps back"),
        K("tracker_sigma_mm", T::kNumber).Unit("mm").Above(0).Max(10).Default("0.01")
            .Doc("the tracker's datasheet sigma per axis (told)"),
        K("encoder_sigma_deg", T::kNumber).Unit("deg").Min(0).Max(0.5).Default("0")
            .Doc("the encoders' datasheet noise, for the diagnosis' noise floor"),
        K("diagnosis", T::kSection).Of("tracker_diagnosis").Doc("model discovery"),
        K("payload", T::kSection).Of("tracker_payload").Default("none")
            .Doc("what the flange carries besides the reflector, as weighed and drawn")}});
  s.push_back(
      {"tracker_payload", "A told payload for the gravity terms.",
       {K("mass_kg", T::kNumber).Required().Unit("kg").Min(0).Max(50).Doc("as weighed"),
        K("xyz_mm", T::kNumbers).Required().Unit("mm").Count(3)
            .Doc("its centre of mass in the flange frame, by drawing (within 1000 mm)")}});
  s.push_back({"tracker_diagnosis", "Model discovery on the tracker's points "
                                    "(bench/io/diagnosis_config.h).",
               DiagnosisKeys(false)});
  s.push_back(
      {"acceptance_criterion", "A criterion on a report.json figure: max and/or min (at least "
                               "one, inclusive; min <= max).",
       {K("figure", T::kString).Required().Counts(1, 500)
            .Doc("key path into report.json: keys joined by '.', array items as [i] or .i, "
                 "from a top-level key of the report (robots.<name> naming a robot of the "
                 "scenario)"),
        K("max", T::kNumber).Doc("the figure is at most this"),
        K("min", T::kNumber).Doc("the figure is at least this"),
        K("name", T::kString).Counts(1, 200).Default("the figure and its bounds")
            .Doc("the JUnit test case's name")},
       false,
       {},
       {{"max", "min"}}});
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
        K("calibration", T::kSection).Of("calibration").OnlyWithRobots(2)
            .Doc("the optical-axis procedure (bench/io/calibration_config.h)"),
        K("handclasp", T::kSection).Of("handclasp").OnlyWithRobots(2)
            .Doc("the handclasp base-frame procedure (bench/runs/handclasp_run.h)"),
        K("tracker_calibration", T::kSection).Of("tracker_calibration").RequiredWithRobots(1)
            .Doc("the tracker procedure (bench/runs/tracker_run.h)"),
        K("acceptance", T::kSectionList).Of("acceptance_criterion").Counts(1, 100)
            .Doc("criteria on report.json figures (bench/report/acceptance.h)")}});
  s.back().keys[4].tuple = {"robot1", "robot2"};
  s.push_back({"seeds", "The two independent random streams (trial t of a study adds t).",
               {K("truth", T::kUnsigned).Default("1").Doc("the twin's draws"),
                K("estimator", T::kUnsigned).Default("1").Doc("the estimator's own randomness"),
                K("noise", T::kUnsigned).Doc(
                    "optional: the twin's draws while it runs (encoder, image, tracker and "
                    "temperature noise, the operator's error) from this seed instead of truth's; "
                    "the same truth measured again (a repeatability study, a paired study's "
                    "control)")}});
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
        K("skybox", T::kBoolean).Default("true")
            .Doc("draw the sky behind the scene (false: black, faster)"),
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
  AddProcedureSections(&s);
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
