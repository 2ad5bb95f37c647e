#include "bench/runs/tracker_run.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <utility>

#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include "bench/io/model_loader.h"
#include "bench/io/model_yaml.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "bench/io/term_spec_text.h"
#include "bench/io/yaml_util.h"
#include "bench/report/acceptance.h"
#include "bench/io/declared_terms.h"
#include "bench/io/diagnosis_config.h"
#include "bench/report/diagnosis_report.h"
#include "bench/report/report_units.h"
#include "bench/report/scenario_json.h"
#include "bench/scoring/calibration_scoring.h"
#include "calib/common/errors.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/model/parameter_layout.h"
#include "calib/model/robot_model.h"
#include "calib/identification/engine.h"
#include "calib/procedures/tracker_procedure.h"
#include "sim/cell/twin_cell.h"
#include "sim/world/mujoco_handles.h"

namespace twin {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const YamlKeys kTrackerCalibrationKeys = {"robot",    "told_reflector_mm", "poses",
                                          "max_attempts", "joint_margin_deg", "holdout",
                                          "tracker_sigma_mm", "encoder_sigma_deg", "diagnosis",
                                          "payload"};
const YamlKeys kPayloadKeys = {"mass_kg", "xyz_mm"};

struct TrackerRunConfig {
  int robot = 1;
  Vector3 told_p_F = Vector3::Zero();
  TrackerProcedureOptions procedure;
  double told_sigma_m = 1e-5;  // the tracker's datasheet accuracy per axis
  bool diagnosis = true;
  DiscoveryOptions discovery;
  int truth_poses = 60;        // poses of the physical-truth scoring of the discovered model
  double payload_kg = 0.0;     // told: weighed
  Vector3 payload_p_F = Vector3::Zero();  // told: its centre of mass in the flange, by drawing
};

TrackerRunConfig ParseTrackerRunConfig(const Scenario& sc) {
  const YamlReader r(sc.path);
  const YamlMap m(r, sc.tracker_calibration, kTrackerCalibrationKeys);
  TrackerRunConfig c;
  const YamlField robot = m.Get("robot");
  const std::string name = r.String(robot);
  c.robot = -1;
  for (int k = 0; k < kNumRobots; ++k) {
    if (sc.robot_names[k] == name) c.robot = k;
  }
  if (c.robot < 0) r.Fail(robot, "names no robot of the scenario: '" + name + "'");
  const YamlField told = m.Get("told_reflector_mm");
  c.told_p_F = r.Vector(told) / 1000.0;
  if (!(c.told_p_F.norm() <= 0.5)) {
    r.Fail(told, "must lie within 500 mm of the flange (a reflector's bracket)");
  }
  const YamlField poses = m.Get("poses");
  c.procedure.poses = r.Integer(poses);
  if (c.procedure.poses < 1 || c.procedure.poses > 100000) r.Fail(poses, "expected 1 to 100000");
  if (const auto f = m.Find("max_attempts", false)) {
    c.procedure.max_attempts = r.Integer(*f);
    if (c.procedure.max_attempts < c.procedure.poses || c.procedure.max_attempts > 1000000) {
      r.Fail(*f, "expected poses to 1000000 attempts");
    }
  }
  if (const auto f = m.Find("joint_margin_deg", false)) {
    const double v = r.Number(*f);
    if (!(v >= 0.0 && v <= 45.0)) r.Fail(*f, "expected 0 to 45 deg");
    c.procedure.joint_margin_rad = DegToRad(v);
  }
  if (const auto f = m.Find("holdout", false)) {
    const double v = r.Number(*f);
    if (!(v > 0.0 && v <= 0.5)) r.Fail(*f, "expected a fraction in (0, 0.5]");
    c.procedure.calibration.holdout_fraction = v;
  }
  if (const auto f = m.Find("tracker_sigma_mm", false)) {
    const double v = r.Number(*f);
    if (!(v > 0.0 && v <= 10.0)) r.Fail(*f, "expected 0 < sigma <= 10 mm");
    c.told_sigma_m = v / 1000.0;
  }
  c.procedure.calibration.set.default_sigma = c.told_sigma_m;
  if (const auto f = m.Find("encoder_sigma_deg", false)) {
    const double v = r.Number(*f);
    if (!(v >= 0.0 && v <= 0.5)) r.Fail(*f, "expected 0 to 0.5 deg");
    c.discovery.joint_sigma_rad = DegToRad(v);
  }
  c.procedure.seed = sc.seeds.estimator;
  c.procedure.calibration.seed = sc.seeds.estimator;
  c.discovery.seed = sc.seeds.estimator;
  c.discovery.set.default_sigma = c.told_sigma_m;
  if (const auto f = m.Find("payload", false)) {
    const YamlMap pm(r, *f, kPayloadKeys);
    const YamlField mass = pm.Get("mass_kg");
    c.payload_kg = r.Number(mass);
    // A flange-mounted target with its bracket on an arm that also carries a reflector.
    if (!(c.payload_kg >= 0.0 && c.payload_kg <= 50.0)) r.Fail(mass, "expected 0 to 50 kg");
    const YamlField at = pm.Get("xyz_mm");
    c.payload_p_F = r.Vector(at) / 1000.0;
    if (!(c.payload_p_F.norm() <= 1.0)) r.Fail(at, "must lie within 1000 mm of the flange");
  }
  if (const auto f = m.Find("diagnosis", false)) {
    DiagnosisConfig d;
    ParseDiagnosisSection(r, *f, sc.twin.robots[c.robot].model, &d, &c.discovery);
    c.diagnosis = d.enabled;
    c.truth_poses = d.truth_poses;
  }
  return c;
}

json Stats(const PositionErrorStats& s) { return {{"rms", 1e3 * s.rms}, {"max", 1e3 * s.max}}; }

void WriteFile(const fs::path& path, const std::string& text) { WriteTextFile(path.string(), text); }

std::string Html(const json& j) {
  std::ostringstream os;
  os << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tracker calibration "
     << j["scenario"]["name"].get<std::string>() << "</title><style>body{font-family:sans-serif}"
     << "td,th{padding:2px 8px;text-align:right}</style></head><body><h1>Laser-tracker "
        "calibration: "
     << j["scenario"]["name"].get<std::string>() << "</h1>";
  os << "<h2>Truth position error (200 random configurations) [mm]</h2><table><tr><th>gauge"
        "</th><th>before RMS</th><th>after RMS</th><th>after max</th></tr>";
  for (const char* g : {"raw", "rigid"}) {
    const json& t = j["truth_position_error_mm"][g];
    os << "<tr><td>" << g << "</td><td>" << t["before"]["rms"] << "</td><td>" << t["after"]["rms"]
       << "</td><td>" << t["after"]["max"] << "</td></tr>";
  }
  os << "</table><h2>Held-out points [mm]</h2><table><tr><th>split</th><th>poses</th><th>"
        "before RMS</th><th>after RMS</th><th>after max</th><th></th></tr>";
  for (const auto& [name, s] : j["heldout"].items()) {
    os << "<tr><td>" << name << "</td><td>" << s["after"]["poses"] << "</td><td>"
       << s["before"]["rms_mm"] << "</td><td>" << s["after"]["rms_mm"] << "</td><td>"
       << s["after"]["max_mm"] << "</td><td>" << (s["worse"].get<bool>() ? "WORSE" : "")
       << "</td></tr>";
  }
  os << "</table><h2>Parameters (deviation from nominal)</h2><table><tr><th>name</th><th>unit"
        "</th><th>estimated</th><th>true</th><th>sigma</th></tr>";
  for (const json& p : j["parameters"]) {
    os << "<tr><td>" << p["name"].get<std::string>() << "</td><td>" << p["unit"].get<std::string>()
       << "</td><td>" << p["estimated"] << "</td><td>" << p["true"] << "</td><td>" << p["sigma"]
       << "</td></tr>";
  }
  os << "</table><h2>Unidentifiable</h2><ul>";
  for (const json& u : j["unidentifiable"]) os << "<li>" << u.get<std::string>() << "</li>";
  os << "</ul>";
  if (j.contains("diagnosis")) os << DiagnosisHtml(j["diagnosis"]);
  os << "</body></html>\n";
  return os.str();
}

/// The scenario of a run (as the trial), its tracker section and acceptance criteria, checked.
struct TrackerRunSetup {
  Scenario sc;
  TrackerRunConfig config;
  Acceptance acceptance;
};

// Loads and checks the scenario and its tracker section, and checks the output paths.
TrackerRunSetup LoadTrackerRun(const RunOptions& o) {
  Scenario sc = LoadScenario(o.scenario);
  ApplyTrial(o.trial, &sc);
  ValidateTrackerScenario(sc);
  TrackerRunConfig config = ParseTrackerRunConfig(sc);
  Acceptance acceptance = ParseAcceptance(sc);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  // Built in place, never assigned: assigning a YAML::Node (the sections) is no plain copy.
  return {std::move(sc), std::move(config), std::move(acceptance)};
}

// Told: the nominal model with the drawn reflector and the weighed payload. Never the truth.
KinematicModel ToldModel(const TrackerRunSetup& setup) {
  const Scenario& sc = setup.sc;
  const TrackerRunConfig& config = setup.config;
  const int robot = config.robot;
  const std::string name = sc.robot_names[robot];
  // Told: the nominal model with the drawn reflector. Never the truth.
  KinematicModel nominal = WithReflector(sc.twin.robots[robot].model, config.told_p_F);
  nominal.name = name;
  // The payload the engineer weighed and drew (tracker_calibration.payload, told; never the
  // twin's board): its mass at its drawn centre of mass, on the tool link (whose frame is the
  // reflector's, turned about z by the tool link's theta) so that the gravity torques of error
  // terms see it.
  if (config.payload_kg > 0.0) {
    Link& tool = nominal.tool();
    const Matrix3 R_FLt = Eigen::AngleAxisd(tool.dh.theta_offset, Vector3::UnitZ()).toRotationMatrix();
    AddPointMass(config.payload_kg, R_FLt.transpose() * (config.payload_p_F - config.told_p_F),
                 &tool);
  }
  return nominal;
}

/// The procedure's outcome: the declared starting model, its notes and the measured points.
struct ProcedureOutcome {
  std::vector<std::string> notes;  ///< DeclaredModel's notes, reported as warnings
  RobotModel start;                ///< the estimator's starting model (told, declared terms)
  TrackerProcedureResult result;   ///< the points, the skips and the calibration
};

// Announces the run, builds the declared starting model and runs the tracker procedure.
ProcedureOutcome RunProcedure(const RunOptions& o, const TrackerRunSetup& setup,
                              const KinematicModel& nominal, TwinCell* cell) {
  const Scenario& sc = setup.sc;
  const int robot = setup.config.robot;
  const std::string name = sc.robot_names[robot];
  if (!o.quiet) {
    std::printf("twinbench run: tracker calibration of %s, scenario %s (%s)\n", name.c_str(),
                sc.name.c_str(), sc.path.c_str());
  }
  ProcedureOutcome procedure;
  procedure.start = DeclaredModel(sc, robot, nominal, &procedure.notes);
  try {
    procedure.result = RunTrackerProcedure(*cell, robot, procedure.start, setup.config.procedure);
  } catch (const InputError& e) {
    throw InputError(sc.path + " scenario.tracker_calibration", e.what());
  }
  return procedure;
}

/// Model discovery's outcome, when it ran.
struct TrackerDiagnosis {
  bool ran = false;        ///< false with --no-diagnosis or diagnosis.enabled: false
  DiscoveryResult result;  ///< the discovered model and the verdict (when it ran)
};

// Model discovery (estimator side: the points and the starting model only).
TrackerDiagnosis DiscoverModel(const RunOptions& o, const TrackerRunSetup& setup,
                               const ProcedureOutcome& procedure) {
  TrackerDiagnosis diagnosis;
  diagnosis.ran = o.diagnosis && setup.config.diagnosis;
  if (diagnosis.ran) {
    DiscoveryOptions d = setup.config.discovery;
    d.set.source = "tracker_calibration";
    if (!o.quiet) {
      d.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
    }
    try {
      diagnosis.result = DiscoverTrackerModel(procedure.start, procedure.result.points, d);
    } catch (const InputError& e) {
      throw InputError(setup.sc.path + " scenario.tracker_calibration.diagnosis", e.what());
    }
  }
  return diagnosis;
}

/// The physical truth's points [m, base frame]: the reflector where the twin's physics puts it,
/// and where the calibrated and the discovered model put it at the same readings.
struct PhysicalTruth {
  std::vector<Vector3> true_points, calibrated, discovered;  ///< discovered: when diagnosed
};

// Physical truth (bench only): the reflector where the twin's physics puts it (every effect
// included) at seeded random poses the twin reaches, against the delivered (calibrated,
// geometric plus declared terms) model and the discovered one, at the same readings.
PhysicalTruth MeasurePhysicalTruth(const TrackerRunSetup& setup, const KinematicModel& nominal,
                                   const ProcedureOutcome& procedure,
                                   const TrackerDiagnosis& diagnosis, TwinCell* cell) {
  const TrackerRunConfig& config = setup.config;
  const int robot = config.robot;
  const TrackerProcedureResult& result = procedure.result;
  const IdentificationResult& id = result.calibration.identified;
  PhysicalTruth physical;
  std::mt19937_64 rng(setup.sc.seeds.truth * 7919 + 17);
  const double margin = config.procedure.joint_margin_rad;
  for (int a = 0; a < 20 * config.truth_poses &&
                  static_cast<int>(physical.true_points.size()) < config.truth_poses; ++a) {
    JointVector q = ZeroJoints(nominal);
    for (int i = 0; i < nominal.num_joints(); ++i) {
      const JointLimits& l = nominal.links[i].limits;
      q(i) = std::uniform_real_distribution<double>(l.lower + margin, l.upper - margin)(rng);
    }
    const JointVector before = cell->ReadEncoders(robot);
    if (cell->MoveTo(robot, q).status != MoveStatus::kSettled) continue;
    MeasurementContext c;
    c.q = cell->ReadEncoders(robot);
    c.approach = ApproachDirections(before, q);
    c.time_s = cell->MeasureTracker(robot).time_s;
    // The sensor's reading, against the session's reference, as the procedure records it.
    if (std::isfinite(result.temperature_reference_C)) {
      c.temperature_delta_K = cell->ReadTemperatureC(robot) - result.temperature_reference_C;
    }
    const TwinTruth t = cell->Truth();
    physical.true_points.push_back(t.X_WB[robot].inverse() * (t.X_WF[robot] * t.tracker.p_FR));
    physical.calibrated.push_back(EndPose(id.model, c).translation());
    if (diagnosis.ran) physical.discovered.push_back(EndPose(diagnosis.result.model, c).translation());
  }
  return physical;
}

// The identifiable combinations' true values. The true value of a combination is what the
// same identification finds from noise-free points of the true arm (true geometry and
// reflector, the true tracker pose) at the same readings: a linear projection of the true
// parameters onto the combinations would differ from it by second-order terms of the
// unidentifiable part (millimetre errors: microns), more than the reported sigmas.
Eigen::VectorXd TrueCombinations(const TwinTruth& truth, int robot,
                                 const KinematicModel& true_model, const KinematicModel& nominal,
                                 const TrackerProcedureResult& result) {
  const IdentificationResult& id = result.calibration.identified;
  Eigen::VectorXd z_true = Eigen::VectorXd::Zero(id.z.size());
  const Transform X_TB = truth.tracker.X_WT.inverse() * truth.X_WB[robot];
  std::vector<TrackerPoint> exact = result.points;
  for (TrackerPoint& p : exact) {
    p.p_T = X_TB * EndPose(true_model, p.context.q).translation();
    p.sigma = 0.0;
  }
  TrackerSet set(exact);
  const IdentificationResult ref = Identify(MakeRobotModel(nominal), {&set});
  // In the delivered identification's basis (the reference's SVD may order or sign its
  // directions otherwise): the reference correction's coordinates along id's directions.
  const Eigen::MatrixXd& B = id.identifiable_directions;
  if (ref.status != IdentificationStatus::kFailed && ref.correction.size() == B.rows()) {
    z_true = (B.transpose() * B).ldlt().solve(B.transpose() * ref.correction);
  }
  return z_true;
}

/// The scores against the true geometry with the true reflector.
struct TruthScores {
  GaugeErrors before, after;       ///< nominal and identified, 200 random configurations
  Eigen::VectorXd phi0, phi_true;  ///< the nominal and the true geometric parameters
  int within3 = 0;                 ///< identifiable combinations within 3 sigma of the truth
  json items;                      ///< each combination: estimated, true, sigma
};

// Scoring against the truth (bench only): the true geometry with the true reflector.
TruthScores ScoreAgainstTruth(const TwinTruth& truth, int robot, const KinematicModel& nominal,
                              const TrackerProcedureResult& result) {
  const IdentificationResult& id = result.calibration.identified;
  TruthScores scores;
  const KinematicModel true_model = WithReflector(truth.models[robot], truth.tracker.p_FR);
  const std::vector<JointVector> configs =
      RandomJointConfigurations(nominal, 200, 1, DegToRad(10.0));
  std::vector<Vector3> p_true, p_nominal, p_identified;
  for (const JointVector& q : configs) {
    p_true.push_back(EndPose(true_model, q).translation());
    p_nominal.push_back(EndPose(nominal, q).translation());
    p_identified.push_back(EndPose(id.model.chain, q).translation());
  }
  scores.before = CompareInGauges(p_nominal, p_true);
  scores.after = CompareInGauges(p_identified, p_true);
  // The identifiable combinations against their true values.
  scores.phi0 = GetParameters(nominal);
  scores.phi_true = GetParameters(true_model);
  const Eigen::VectorXd z_true = TrueCombinations(truth, robot, true_model, nominal, result);
  int& within3 = scores.within3;
  json& items = scores.items;
  items = json::array();
  for (int k = 0; k < id.z.size(); ++k) {
    const double sigma = std::sqrt(std::max(0.0, id.covariance_z(k, k)));
    const bool ok = std::abs(id.z(k) - z_true(k)) <= 3.0 * sigma;
    within3 += ok;
    items.push_back({{"index", k}, {"estimated", id.z(k)}, {"true", z_true(k)}, {"sigma", sigma},
                     {"within_3_sigma", ok}});
  }
  return scores;
}

/// Everything a tracker run's report, files and summary are made from.
struct TrackerRunRecord {
  const RunOptions& options;
  const TrackerRunSetup& setup;
  const KinematicModel& nominal;      ///< told
  const ProcedureOutcome& procedure;
  const TrackerDiagnosis& diagnosis;
  const PhysicalTruth& physical;
  const TwinTruth& truth;             ///< after the physical-truth poses
  const TruthScores& scores;
};

// The report's head: the scenario, the procedure, the tracker's points and skips, the
// held-out splits and the truth position errors.
json ReportHead(const TrackerRunRecord& r) {
  const Scenario& sc = r.setup.sc;
  const TrackerProcedureResult& result = r.procedure.result;
  json j;
  j["scenario"] = ScenarioJson(sc);
  j["procedure"] = "laser-tracker calibration (geometry, tracker pose, reflector offset)";
  j["robot"] = sc.robot_names[r.setup.config.robot];
  j["tracker"] = {{"poses", result.points.size()}, {"attempts", result.attempts},
                  {"sigma_mm", 1e3 * r.truth.tracker.sigma_m}};
  // The robot's temperature sensor (the points carry their change from this first reading).
  j["tracker"]["temperature_reference_C"] =
      std::isfinite(result.temperature_reference_C) ? json(result.temperature_reference_C)
                                                    : json(nullptr);
  j["tracker"]["skipped"] = json::array();
  for (const TrackerSkip& s : result.skipped) {
    j["tracker"]["skipped"].push_back({{"attempt", s.attempt}, {"reason", s.reason}});
  }
  for (const HeldOutSplit& s : result.calibration.splits) {
    j["heldout"][s.name] = {{"rule", s.rule}, {"training_poses", s.training},
                            {"before", PointErrorsJson(s.before)}, {"after", PointErrorsJson(s.after)},
                            {"worse", s.worse}};
  }
  const GaugeErrors& before = r.scores.before;
  const GaugeErrors& after = r.scores.after;
  j["truth_position_error_mm"] = {
      {"raw", {{"before", Stats(before.raw)}, {"after", Stats(after.raw)}}},
      {"rigid", {{"before", Stats(before.rigid)}, {"after", Stats(after.rigid)}}}};
  return j;
}

// Adds the parameters against their true values, the declared terms' parameters, the
// identifiable combinations and the identification's figures to the report.
void AddParameterReport(const TrackerRunRecord& r, json* report) {
  json& j = *report;
  const IdentificationResult& id = r.procedure.result.calibration.identified;
  const Eigen::VectorXd& phi0 = r.scores.phi0;
  const Eigen::VectorXd& phi_true = r.scores.phi_true;
  j["parameters"] = json::array();
  const ParameterLayout layout(MakeRobotModel(r.nominal));
  for (int i = 0; i < phi0.size(); ++i) {
    const IdentifiedParameter& p = id.parameters[i];
    j["parameters"].push_back({{"name", p.name},
                               {"unit", ReportUnit(p.unit)},
                               {"estimated", ReportValue(p.estimated - phi0(i), p.unit)},
                               {"true", ReportValue(phi_true(i) - phi0(i), p.unit)},
                               {"sigma", ReportValue(p.sigma, p.unit)}});
  }
  // The declared terms' parameters as identified (no truth beside them: a term's parameters
  // are the estimator's, the twin's effect need not have the same ones).
  j["declared_term_parameters"] = json::array();
  for (std::size_t i = phi0.size(); i < id.parameters.size(); ++i) {
    const IdentifiedParameter& p = id.parameters[i];
    j["declared_term_parameters"].push_back({{"name", p.name},
                                             {"unit", ReportUnit(p.unit)},
                                             {"estimated", ReportValue(p.estimated, p.unit)},
                                             {"sigma", ReportValue(p.sigma, p.unit)}});
  }
  j["identifiable_combinations"] = {{"count", id.z.size()}, {"within_3_sigma", r.scores.within3},
                                    {"items", r.scores.items}};
  j["unidentifiable"] = id.observability.unidentifiable;
  j["condition_number"] = id.condition_number();
  j["sigma0"] = id.sigma0;
  j["declared_terms"] = json::array();
  for (const auto& t : r.procedure.start.terms) j["declared_terms"].push_back(TermLabel(t->spec()));
}

// Adds the physical truth's errors of the calibrated (and the discovered) model, when the
// twin reached some of its poses.
void AddPhysicalTruthReport(const TrackerRunRecord& r, json* report) {
  json& j = *report;
  const PhysicalTruth& physical = r.physical;
  if (!physical.true_points.empty()) {
    const GaugeErrors calibrated = CompareInGauges(physical.calibrated, physical.true_points);
    j["truth_position_error_mm_physical"] = {
        {"poses", physical.true_points.size()},
        {"rule", "the reflector where the twin's physics puts it (every effect) at seeded random "
                 "poses, against each model at the same readings"},
        {"calibrated_model",
         {{"raw", Stats(calibrated.raw)}, {"rigid", Stats(calibrated.rigid)}}}};
    if (r.diagnosis.ran) {
      const GaugeErrors discovered = CompareInGauges(physical.discovered, physical.true_points);
      j["truth_position_error_mm_physical"]["discovered_model"] = {
          {"raw", Stats(discovered.raw)}, {"rigid", Stats(discovered.rigid)}};
      j["truth_position_error_mm_discovered_model"] = {{"raw", Stats(discovered.raw)},
                                                       {"rigid", Stats(discovered.rigid)}};
    }
  }
}

// The whole report.json (before the acceptance verdict): head, parameters, physical truth,
// diagnosis, warnings and the time since `t_start`.
json TrackerReportJson(const TrackerRunRecord& r,
                       const std::chrono::steady_clock::time_point& t_start) {
  json j = ReportHead(r);
  AddParameterReport(r, &j);
  AddPhysicalTruthReport(r, &j);
  if (r.diagnosis.ran) {
    j["diagnosis"] = DiagnosisJson(r.diagnosis.result);
  } else {
    j["diagnosis"] = {{"verdict", nullptr},
                      {"skipped", r.options.diagnosis ? "tracker_calibration.diagnosis.enabled: false"
                                                      : "--no-diagnosis"}};
  }
  j["warnings"] = r.procedure.result.calibration.warnings;
  for (const std::string& n : r.procedure.notes) j["warnings"].push_back(n);
  j["timing_s"] = {{"total", std::chrono::duration<double>(std::chrono::steady_clock::now() -
                                                           t_start).count()}};
  return j;
}

// measurements.csv: the tracker file format, which `twinbench identify` reads back.
std::string MeasurementsCsv(const KinematicModel& nominal, const TrackerProcedureResult& result,
                            double told_sigma_m) {
  std::ostringstream csv;
  csv << std::setprecision(17) << "pose";
  for (int i = 0; i < nominal.num_joints(); ++i) csv << ",q_" << nominal.links[i].name << "_rad";
  const bool temperatures = std::isfinite(result.temperature_reference_C);
  csv << ",x_m,y_m,z_m,sigma_m,time_s" << (temperatures ? ",temperature_delta_K" : "") << "\n";
  for (const TrackerPoint& p : result.points) {
    csv << p.row;
    for (int i = 0; i < p.context.q.size(); ++i) csv << "," << p.context.q(i);
    csv << "," << p.p_T.x() << "," << p.p_T.y() << "," << p.p_T.z() << "," << told_sigma_m
        << "," << p.context.time_s;
    if (temperatures) csv << "," << p.context.temperature_delta_K;
    csv << "\n";
  }
  return csv.str();
}

// Writes report.json, report.html (unless images are off), measurements.csv and
// identified_<robot>.yaml into a staging folder and publishes it as the output folder.
void WriteTrackerOutputs(const TrackerRunRecord& r, const json& j, const std::string& csv) {
  const RunOptions& o = r.options;
  const std::string name = r.setup.sc.robot_names[r.setup.config.robot];
  const IdentificationResult& id = r.procedure.result.calibration.identified;
  const fs::path out(o.out_dir);
  const std::string staging = CreateStagingDirectory(o.out_dir);
  try {
    WriteFile(fs::path(staging) / "report.json", j.dump(2) + "\n");
    if (o.images) WriteFile(fs::path(staging) / "report.html", Html(j));
    WriteFile(fs::path(staging) / "measurements.csv", csv);
    WriteFile(fs::path(staging) / ("identified_" + name + ".yaml"), ModelToYaml(id.model.chain));
    PublishDirectory(staging, out.string());
  } catch (...) {
    DiscardStaging(staging);
    throw;
  }
}

// Prints the summary: poses, combinations within 3 sigma of the truth, the truth and held-out
// RMS, the diagnosis with its physical truth, and what was written.
void PrintTrackerSummary(const TrackerRunRecord& r, const json& j) {
  const std::string name = r.setup.sc.robot_names[r.setup.config.robot];
  const TrackerProcedureResult& result = r.procedure.result;
  const IdentificationResult& id = result.calibration.identified;
  const GaugeErrors& before = r.scores.before;
  const GaugeErrors& after = r.scores.after;
  const fs::path out(r.options.out_dir);
  std::printf("%s: %zu poses measured (%zu skipped), %d identifiable combinations, %d within 3 "
              "sigma of the truth\n",
              name.c_str(), result.points.size(), result.skipped.size(),
              static_cast<int>(id.z.size()), r.scores.within3);
  std::printf("truth RMS (200 configurations): raw %.4f -> %.4f mm, rigid %.4f -> %.4f mm\n",
              1e3 * before.raw.rms, 1e3 * after.raw.rms, 1e3 * before.rigid.rms,
              1e3 * after.rigid.rms);
  for (const HeldOutSplit& s : result.calibration.splits) {
    std::printf("held-out %-6s %3d poses: %.4f -> %.4f mm%s\n", s.name.c_str(), s.after.poses,
                1e3 * s.before.rms, 1e3 * s.after.rms, s.worse ? "  WORSE" : "");
  }
  if (r.diagnosis.ran) {
    std::printf("%s", DiagnosisSummary(r.diagnosis.result).c_str());
    if (j.contains("truth_position_error_mm_physical")) {
      const json& ph = j["truth_position_error_mm_physical"];
      std::printf("physical truth (%d poses, rigid RMS): calibrated %.4f mm, discovered %.4f mm\n",
                  ph["poses"].get<int>(), ph["calibrated_model"]["rigid"]["rms"].get<double>(),
                  ph["discovered_model"]["rigid"]["rms"].get<double>());
    }
  }
  std::printf("wrote %s/{report.json, report.html, measurements.csv, identified_%s.yaml}\n",
              out.string().c_str(), name.c_str());
}

}  // namespace

void ValidateTrackerScenario(const Scenario& sc) {
  const TrackerRunConfig config = ParseTrackerRunConfig(sc);
  if (!sc.twin.tracker.present) {
    throw InputError(sc.path + " scenario.tracker_calibration",
                     "the cell has no tracker: add a `tracker:` section (bench/io/scenario.h)");
  }
  if (IsPresent(sc.calibration) || IsPresent(sc.handclasp)) {
    throw InputError(sc.path + " scenario.tracker_calibration",
                     "a tracker scenario has no calibration or handclasp section (one "
                     "procedure a scenario)");
  }
  if (config.robot != sc.twin.tracker.robot) {
    throw InputError(sc.path + " scenario.tracker_calibration.robot",
                     "the tracker's reflector is on robot '" +
                         sc.robot_names[sc.twin.tracker.robot] + "', not on '" +
                         sc.robot_names[config.robot] + "'");
  }
}

int RunTrackerScenario(const RunOptions& o) {
  const auto t_start = std::chrono::steady_clock::now();
  // The scenario (as the trial) and its tracker section, checked with the output paths.
  const TrackerRunSetup setup = LoadTrackerRun(o);
  InstallMujocoErrorHandlers();
  TwinCell cell(setup.sc.twin, setup.sc.path);
  // Told: the nominal model with the drawn reflector and payload. Never the truth.
  const KinematicModel nominal = ToldModel(setup);
  // The tracker procedure on the twin, from the declared starting model.
  const ProcedureOutcome procedure = RunProcedure(o, setup, nominal, &cell);
  // Model discovery (estimator side: the points and the starting model only).
  const TrackerDiagnosis diagnosis = DiscoverModel(o, setup, procedure);
  // Physical truth (bench only): the reflector where the twin's physics puts it.
  const PhysicalTruth physical = MeasurePhysicalTruth(setup, nominal, procedure, diagnosis, &cell);
  // Scoring against the truth (bench only): the true geometry with the true reflector.
  const TwinTruth truth = cell.Truth();
  const TruthScores scores = ScoreAgainstTruth(truth, setup.config.robot, nominal, procedure.result);
  const TrackerRunRecord record{o, setup, nominal, procedure, diagnosis, physical, truth, scores};
  // The report and its acceptance verdict.
  json j = TrackerReportJson(record, t_start);
  const AcceptanceVerdict verdict = EvaluateAcceptance(setup.acceptance, &j);
  // measurements.csv: the tracker file format, which `twinbench identify` reads back.
  const std::string csv = MeasurementsCsv(nominal, procedure.result, setup.config.told_sigma_m);
  // The output folder, written in full or not at all.
  WriteTrackerOutputs(record, j, csv);
  // The summary on the terminal.
  if (!o.quiet) PrintTrackerSummary(record, j);
  if (!o.junit.empty()) {
    WriteJunit(o.junit, setup.sc.name, verdict,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
  }
  PrintVerdict(verdict);
  return VerdictExitCode(verdict);
}

}  // namespace twin
