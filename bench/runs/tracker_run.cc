#include "bench/runs/tracker_run.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <utility>

#include <Eigen/Cholesky>

#include "bench/io/model_loader.h"
#include "bench/io/model_yaml.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "bench/io/scenario_keys.h"
#include "bench/io/term_spec_text.h"
#include "bench/io/yaml_util.h"
#include "bench/report/acceptance.h"
#include "bench/io/declared_terms.h"
#include "bench/io/diagnosis_config.h"
#include "bench/report/diagnosis_report.h"
#include "bench/report/tracker_report.h"
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

namespace {

const YamlKeys kTrackerCalibrationKeys = ScenarioKeyNames("tracker_calibration");
const YamlKeys kPayloadKeys = ScenarioKeyNames("tracker_payload");

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
  for (std::size_t k = 0; k < sc.robot_names.size(); ++k) {
    if (sc.robot_names[k] == name) c.robot = static_cast<int>(k);
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

void WriteFile(const fs::path& path, const std::string& text) { WriteTextFile(path.string(), text); }

/// The scenario of a run (as the trial), its tracker section and acceptance criteria, checked.
struct TrackerRunSetup {
  Scenario sc;
  std::string text;  ///< the scenario's text (a recording keeps it)
  TrackerRunConfig config;
  Acceptance acceptance;
};

// Loads and checks the scenario and its tracker section, and checks the output paths.
TrackerRunSetup LoadTrackerRun(const RunOptions& o) {
  std::string text;
  Scenario sc = LoadRunScenario(o, &text);
  ValidateTrackerScenario(sc, !o.cell.address.empty());
  TrackerRunConfig config = ParseTrackerRunConfig(sc);
  Acceptance acceptance = ParseAcceptance(sc);
  ValidateOutputFolder(o.out_dir, "--out");
  if (!o.junit.empty()) ValidateJunitFile(o.junit, o.out_dir);
  // Built in place, never assigned: assigning a YAML::Node (the sections) is no plain copy.
  return {std::move(sc), std::move(text), std::move(config), std::move(acceptance)};
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
                              const KinematicModel& nominal, BenchCell* cell) {
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
                                   const TrackerDiagnosis& diagnosis, BenchCell* cell) {
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

// Scoring against the truth (bench only): the true geometry with the true reflector.
TrackerTruthScores ScoreAgainstTruth(const TwinTruth& truth, int robot,
                                     const KinematicModel& nominal,
                                     const TrackerProcedureResult& result) {
  const IdentificationResult& id = result.calibration.identified;
  TrackerTruthScores scores;
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
  for (int k = 0; k < id.z.size(); ++k) {
    const double sigma = std::sqrt(std::max(0.0, id.covariance_z(k, k)));
    const bool ok = std::abs(id.z(k) - z_true(k)) <= 3.0 * sigma;
    scores.within3 += ok;
    scores.combinations.push_back({k, id.z(k), z_true(k), sigma, ok});
  }
  return scores;
}

/// Everything a tracker run's files and summary are made from.
struct TrackerRunRecord {
  const RunOptions& options;
  const TrackerRunSetup& setup;
  const ProcedureOutcome& procedure;
  const TrackerRunResult& result;  ///< the typed result the report is made of
};

// The physical truth's errors of the calibrated (and the discovered) model, when the twin
// reached some of its poses.
TrackerPhysicalTruthScores ScorePhysicalTruth(const PhysicalTruth& physical, bool diagnosed) {
  TrackerPhysicalTruthScores scores;
  if (physical.true_points.empty()) return scores;
  scores.poses = static_cast<int>(physical.true_points.size());
  scores.calibrated = CompareInGauges(physical.calibrated, physical.true_points);
  if (diagnosed) scores.discovered = CompareInGauges(physical.discovered, physical.true_points);
  return scores;
}

// The run's typed result (before the acceptance verdict): what the stages found and the
// scores against the truth; `total_s`: the time since the run began.
TrackerRunResult MakeTrackerResult(const RunOptions& o, const TrackerRunSetup& setup,
                                   const ProcedureOutcome& procedure,
                                   const TrackerDiagnosis& diagnosis, const PhysicalTruth& physical,
                                   const TwinTruth* truth, TrackerTruthScores scores) {
  TrackerRunResult r;
  r.scenario = &setup.sc;
  r.robot = setup.sc.robot_names[setup.config.robot];
  r.procedure = &procedure.result;
  for (const auto& t : procedure.start.terms) r.declared_terms.push_back(TermLabel(t->spec()));
  r.notes = procedure.notes;
  r.truth_available = truth != nullptr;
  r.tracker_sigma_m = truth ? truth->tracker.sigma_m : std::numeric_limits<double>::quiet_NaN();
  r.truth = std::move(scores);
  r.physical = ScorePhysicalTruth(physical, diagnosis.ran);
  if (diagnosis.ran) {
    r.diagnosis = &diagnosis.result;
  } else {
    r.diagnosis_skipped =
        o.diagnosis ? "tracker_calibration.diagnosis.enabled: false" : "--no-diagnosis";
  }
  return r;
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
void WriteTrackerOutputs(const TrackerRunRecord& r, const TrackerReport& report,
                         const std::string& csv) {
  const RunOptions& o = r.options;
  const std::string name = r.setup.sc.robot_names[r.setup.config.robot];
  const IdentificationResult& id = r.procedure.result.calibration.identified;
  const fs::path out(o.out_dir);
  const std::string staging = CreateStagingDirectory(o.out_dir);
  try {
    WriteFile(fs::path(staging) / "report.json", report.json_text);
    if (o.images) WriteFile(fs::path(staging) / "report.html", report.html);
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
void PrintTrackerSummary(const TrackerRunRecord& r) {
  const std::string name = r.setup.sc.robot_names[r.setup.config.robot];
  const TrackerProcedureResult& result = r.procedure.result;
  const IdentificationResult& id = result.calibration.identified;
  const GaugeErrors& before = r.result.truth.before;
  const GaugeErrors& after = r.result.truth.after;
  const fs::path out(r.options.out_dir);
  if (r.result.truth_available) {
    std::printf("%s: %zu poses measured (%zu skipped), %d identifiable combinations, %d within 3 "
                "sigma of the truth\n",
                name.c_str(), result.points.size(), result.skipped.size(),
                static_cast<int>(id.z.size()), r.result.truth.within3);
    std::printf("truth RMS (200 configurations): raw %.4f -> %.4f mm, rigid %.4f -> %.4f mm\n",
                1e3 * before.raw.rms, 1e3 * after.raw.rms, 1e3 * before.rigid.rms,
                1e3 * after.rigid.rms);
  } else {
    std::printf("%s: %zu poses measured (%zu skipped), %d identifiable combinations; the cell "
                "has no truth: nothing scored against it\n",
                name.c_str(), result.points.size(), result.skipped.size(),
                static_cast<int>(id.z.size()));
  }
  for (const HeldOutSplit& s : result.calibration.splits) {
    std::printf("held-out %-6s %3d poses: %.4f -> %.4f mm%s\n", s.name.c_str(), s.after.poses,
                1e3 * s.before.rms, 1e3 * s.after.rms, s.worse ? "  WORSE" : "");
  }
  if (r.result.diagnosis) {
    std::printf("%s", DiagnosisSummary(*r.result.diagnosis).c_str());
    const TrackerPhysicalTruthScores& ph = r.result.physical;
    if (ph.poses > 0 && ph.discovered) {
      std::printf("physical truth (%d poses, rigid RMS): calibrated %.4f mm, discovered %.4f mm\n",
                  ph.poses, 1e3 * ph.calibrated.rigid.rms, 1e3 * ph.discovered->rigid.rms);
    }
  }
  std::printf("wrote %s/{report.json, report.html, measurements.csv, identified_%s.yaml}\n",
              out.string().c_str(), name.c_str());
}

}  // namespace

void ValidateTrackerScenario(const Scenario& sc, bool served_cell) {
  const TrackerRunConfig config = ParseTrackerRunConfig(sc);
  if (!sc.twin.tracker.present && !served_cell) {
    throw InputError(sc.path + " scenario.tracker_calibration",
                     "the cell has no tracker: add a `tracker:` section (bench/io/scenario.h)");
  }
  if (IsPresent(sc.calibration) || IsPresent(sc.handclasp)) {
    throw InputError(sc.path + " scenario.tracker_calibration",
                     "a tracker scenario has no calibration or handclasp section (one "
                     "procedure a scenario)");
  }
  if (sc.twin.tracker.present && config.robot != sc.twin.tracker.robot) {
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
  const std::unique_ptr<BenchCell> owned_cell =
      OpenBenchCell(setup.sc.twin, setup.sc.path, RunCellOptions(o, setup.sc, setup.text));
  BenchCell& cell = *owned_cell;
  // Told: the nominal model with the drawn reflector and payload. Never the truth.
  const KinematicModel nominal = ToldModel(setup);
  // The tracker procedure on the twin, from the declared starting model.
  const ProcedureOutcome procedure = RunProcedure(o, setup, nominal, &cell);
  // Model discovery (estimator side: the points and the starting model only).
  const TrackerDiagnosis diagnosis = DiscoverModel(o, setup, procedure);
  // A cell without truth (a real one): the estimates and the procedure's own figures only.
  const bool scored = cell.HasTruth();
  // Physical truth (bench only): the reflector where the twin's physics puts it.
  const PhysicalTruth physical =
      scored ? MeasurePhysicalTruth(setup, nominal, procedure, diagnosis, &cell) : PhysicalTruth{};
  // Scoring against the truth (bench only): the true geometry with the true reflector.
  std::optional<TwinTruth> truth;
  TrackerTruthScores scores;
  if (scored) {
    truth = cell.Truth();
    scores = ScoreAgainstTruth(*truth, setup.config.robot, nominal, procedure.result);
  } else {
    scores.phi0 = GetParameters(nominal);  // the parameters are reported against the nominal
  }
  cell.Finish();  // the last call: a recording is complete, a replay used up
  TrackerRunResult result = MakeTrackerResult(o, setup, procedure, diagnosis, physical,
                                              truth ? &*truth : nullptr, std::move(scores));
  // Criteria on figures against the truth cannot be judged without it: left out, and said so.
  const Acceptance acceptance =
      scored ? setup.acceptance : WithoutTruthCriteria(setup.acceptance, o.quiet);
  result.total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  const TrackerRunRecord record{o, setup, procedure, result};
  // The report and its acceptance verdict.
  const TrackerReport report = MakeTrackerReport(result, acceptance);
  const AcceptanceVerdict& verdict = report.verdict;
  // measurements.csv: the tracker file format, which `twinbench identify` reads back.
  const std::string csv = MeasurementsCsv(nominal, procedure.result, setup.config.told_sigma_m);
  // The output folder, written in full or not at all.
  WriteTrackerOutputs(record, report, csv);
  // The summary on the terminal.
  if (!o.quiet) PrintTrackerSummary(record);
  if (!o.junit.empty()) {
    WriteJunit(o.junit, setup.sc.name, verdict,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
  }
  PrintVerdict(verdict);
  return VerdictExitCode(verdict);
}

}  // namespace twin
