// twinbench: the command-line entry point. Exit codes (docs/reference/exit-codes-and-safety.md): 0
// success; 2 bad input or a refused procedure, with `error: <where>: <what>` on stderr; 3 a run
// that missed its acceptance criteria; 1 only for our own bugs (`internal error: ...`). An
// interrupted run (SIGINT, SIGTERM, SIGHUP) removes its staging folder and ends by the signal.
#include <malloc.h>

#include <cmath>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/report/acceptance.h"
#include "bench/report/scenario_schema.h"
#include "bench/runs/calibration_run.h"
#include "remote/cell_check.h"
#include "bench/runs/kinematics_benchmark.h"
#include "bench/runs/planning_benchmark.h"
#include "bench/runs/replay_cell.h"
#include "bench/runs/serve_cell.h"
#include "bench/runs/study_merge.h"
#include "bench/runs/study_run.h"
#include "bench/runs/synthetic_measurements.h"
#include "bench/runs/tracker_identify_run.h"
#include "bench/io/tracker_file.h"
#include "bench/io/model_loader.h"
#include "bench/io/data_dir.h"
#include "bench/cli_completion.h"
#include "bench/io/output_files.h"
#include "bench/runs/twin_commands.h"
#include "bench/scaffold/new_scenario.h"
#include "bench/io/urdf_model.h"
#include "bench/io/yaml_util.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/model/parameters.h"
#include "sim/render/gl_context.h"
#include "sim/world/mujoco_handles.h"
#include "twinbench_version.h"  // generated: bench/CMakeLists.txt, twinbench_version

namespace twin {
namespace {

constexpr int kExitUserError = 2;
constexpr int kExitInternalError = 1;

// Parses "a,b,c" into exactly n finite numbers of magnitude at most `limit` (the option's
// plausibility limit, `why` its reason); `option` names the flag in the message. Empty items
// (a trailing comma) are refused.
std::vector<double> ParseList(const std::string& text, int n, const std::string& option,
                              double limit, const std::string& why) {
  std::vector<std::string> items;
  std::string item;
  for (char c : text) {
    if (c == ',') {
      items.push_back(item);
      item.clear();
    } else {
      item += c;
    }
  }
  items.push_back(item);
  if (static_cast<int>(items.size()) != n) {
    throw InputError(option, "expected " + std::to_string(n) + " comma-separated numbers, got '" +
                                 text + "'");
  }
  std::vector<double> v;
  for (const std::string& it : items) {
    double x = 0.0;
    try {
      size_t used = 0;
      x = std::stod(it, &used);
      if (it.find_first_not_of(" \t", used) != std::string::npos) throw std::invalid_argument("");
    } catch (const std::exception&) {
      throw InputError(option, "expected a number, got '" + it + "'");
    }
    if (!std::isfinite(x)) throw InputError(option, "expected a finite number, got '" + it + "'");
    if (std::abs(x) > limit) {
      std::ostringstream os;
      os << "expected numbers within +-" << limit << " (" << why << "), got '" << it << "'";
      throw InputError(option, os.str());
    }
    v.push_back(x);
  }
  return v;
}

// One angle per joint of `model`, in degrees; refused (naming the joint) outside its limits.
JointVector ParseJointsDeg(const std::string& text, const KinematicModel& model,
                           const std::string& option) {
  const int n = model.num_joints();
  const std::vector<double> v =
      ParseList(text, n, option, 720.0, "degrees; no joint travels more than two turns");
  JointVector q(n);
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) {
      throw InputError(option, "joint " + std::to_string(i + 1) + ": expected a finite angle");
    }
    q(i) = DegToRad(v[i]);
    const JointLimits& l = model.links[i].limits;
    if (q(i) < l.lower || q(i) > l.upper) {
      std::ostringstream os;
      const Link& link = model.links[i];
      os << "joint " << i + 1 << " ("
         << (link.joint_name.empty() ? link.name : "'" + link.joint_name + "'") << ") at " << v[i]
         << " deg is outside its limits [" << RadToDeg(l.lower) << ", " << RadToDeg(l.upper)
         << "] deg";
      throw InputError(option, os.str());
    }
  }
  return q;
}

void PrintPose(const char* label, const Transform& X) {
  const Vector3 p = X.translation() * 1e3;
  const Vector3 ypr = X.linear().eulerAngles(2, 1, 0);
  std::printf("%s: xyz [%.4f, %.4f, %.4f] mm, rpy [%.4f, %.4f, %.4f] deg\n", label, p.x(), p.y(),
              p.z(), RadToDeg(ypr(2)), RadToDeg(ypr(1)), RadToDeg(ypr(0)));
}

int RunInfo(const std::string& path, const ModelLinks& links) {
  const KinematicModel m = LoadRobotModelAndWarn(path, links);
  std::printf("robot %s (%s)\n%-18s %12s\n", m.name.c_str(), path.c_str(), "parameter", "value");
  for (int i = 0; i < m.num_parameters(); ++i) {
    const double v = GetParameters(m)(i);
    std::printf("%-18s %12.4f %s\n", ParameterName(m.name, i).c_str(),
                IsLengthParameter(i) ? v * 1e3 : RadToDeg(v), IsLengthParameter(i) ? "mm" : "deg");
  }
  double mass = 0.0;
  for (int i = 0; i < m.num_joints(); ++i) {
    const Link& l = m.links[i];
    mass += l.inertia.mass;
    std::printf("joint %d limits [%.1f, %.1f] deg, link mass %.2f kg\n", i + 1,
                RadToDeg(l.limits.lower), RadToDeg(l.limits.upper), l.inertia.mass);
  }
  std::printf("moving mass %.2f kg\n", mass);
  PrintPose("end frame at q = 0", EndPose(m, ZeroJoints(m)));
  return 0;
}

int RunFk(const std::string& path, const ModelLinks& links, const std::string& q_text) {
  const KinematicModel m = LoadRobotModelAndWarn(path, links);
  const JointVector q = ParseJointsDeg(q_text, m, "--q");
  PrintPose("end frame", EndPose(m, q));
  std::printf("smallest Jacobian singular value: %.6f\n", SmallestJacobianSingularValue(m, q));
  return 0;
}

int RunIk(const std::string& path, const ModelLinks& links, const std::string& xyz,
          const std::string& rpy, const std::string& seed, bool position_only) {
  const KinematicModel m = LoadRobotModelAndWarn(path, links);
  const std::vector<double> p =
      ParseList(xyz, 3, "--xyz", 1e4, "millimetres; no arm reaches 10 m");
  const std::vector<double> r = ParseList(rpy, 3, "--rpy", 360.0, "degrees; angles are periodic");
  Transform target = Transform::Identity();
  target.translation() = Vector3(p[0], p[1], p[2]) * 1e-3;
  target.linear() = RpyToRotation(Vector3(DegToRad(r[0]), DegToRad(r[1]), DegToRad(r[2])));
  const JointVector q0 = seed.empty() ? MidRange(m) : ParseJointsDeg(seed, m, "--seed");
  IkOptions options;
  options.position_only = position_only;
  const IkResult res = SolveIk(m, target, q0, options);
  if (res.status != IkStatus::kSuccess) {
    throw InputError("--xyz/--rpy", std::string("target not solvable (") + ToString(res.status) +
                                        "): " + res.reason);
  }
  std::printf("q [deg]:");
  for (int i = 0; i < m.num_joints(); ++i) std::printf(" %.6f", RadToDeg(res.q(i)));
  std::printf("\nposition error %.3g m, orientation error %.3g rad, %d iterations, %d starts\n",
              res.position_error, res.orientation_error, res.iterations, res.starts);
  return 0;
}

int RunExportUrdf(const std::string& path, const ModelLinks& links, const std::string& out) {
  ValidateOutputFile(out, "--out", {kWrittenByComment});
  WriteFileAtomically(out, ModelToUrdf(LoadRobotModelAndWarn(path, links)));
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

// The kinematic demo run by scripts/run.sh until the twin exists: both robots' YAML and URDF
// descriptions agree, IK round trips, Jacobian conditioning over the workspace.
int RunDemo(const std::string& model_dir, int samples, unsigned seed) {
  std::mt19937_64 rng(seed);
  for (const char* robot : {"reinovo_r1", "reinovo_r2"}) {
    const std::string base = model_dir + "/" + robot;
    const KinematicModel yaml = LoadRobotModel(base + ".yaml");
    const KinematicModel urdf = LoadRobotModel(base + ".urdf");
    double fk_max = 0.0, ik_max = 0.0, sv_min = 1e9;
    int solved = 0;
    for (int k = 0; k < samples; ++k) {
      JointVector q(yaml.num_joints());
      for (int i = 0; i < yaml.num_joints(); ++i) {
        q(i) = std::uniform_real_distribution<double>(yaml.links[i].limits.lower,
                                                      yaml.links[i].limits.upper)(rng);
      }
      const Transform X = EndPose(yaml, q);
      fk_max = std::max(fk_max, (X.translation() - EndPose(urdf, q).translation()).norm());
      sv_min = std::min(sv_min, SmallestJacobianSingularValue(yaml, q));
      const IkResult r = SolveIk(yaml, X, MidRange(yaml));
      if (r.status == IkStatus::kSuccess) {
        ++solved;
        ik_max = std::max(ik_max, (EndPose(yaml, r.q).translation() - X.translation()).norm());
      } else {
        std::printf("  IK failed (%s): %s\n", ToString(r.status), r.reason.c_str());
      }
    }
    std::printf("%s: YAML vs URDF FK max %.2e m over %d random poses; IK solved %d/%d, max "
                "position error %.2e m; smallest Jacobian singular value seen %.4f\n",
                robot, fk_max, samples, solved, samples, ik_max, sv_min);
  }
  return 0;
}

// The values of every verb's options, bound to the command line by the Add*Verb(s) functions.
struct CliValues {
  std::string model, q, xyz, rpy = "0,0,0", seed, out, model_dir;
  bool position_only = false;
  int samples = 200;
  ModelLinks links;  // the chain of a URDF model: one pair for every verb that takes a model file
  unsigned rng_seed = 1;
  RenderOptions render_options;
  TwinBenchmarkOptions bench_options;
  RunOptions run_options;
  bool no_images = false;
  PlanningBenchmarkOptions planning_options;
  StudyOptions study_options;
  std::string shard = "0/1";
  bool study_quiet = false;
  StudyMergeOptions merge_options;
  std::string check_scenario;
  std::string schema_out;
  IdentifyOptions identify_options;
  TrackerIdentifyOptions tracker_options;
  SynthesizeOptions synth_options;
  KinematicsBenchmarkOptions kb_options;
  NewScenarioOptions new_scenario;
  remote::CellCheckOptions cell_check;
  std::string replay_dir, replay_out;
  bool replay_quiet = false, replay_no_images = false;
  ServeCellOptions serve_options;
};

// The verbs (subcommands) of the command line, owned by the CLI::App.
struct Verbs {
  CLI::App* info = nullptr;
  CLI::App* fk = nullptr;
  CLI::App* ik = nullptr;
  CLI::App* export_urdf = nullptr;
  CLI::App* demo = nullptr;
  CLI::App* render = nullptr;
  CLI::App* bench = nullptr;
  CLI::App* run = nullptr;
  CLI::App* bench_planning = nullptr;
  CLI::App* study = nullptr;
  CLI::App* merge = nullptr;
  CLI::App* check = nullptr;
  CLI::App* schema = nullptr;
  CLI::App* identify = nullptr;
  CLI::App* synth = nullptr;
  CLI::App* kbench = nullptr;
  CLI::App* new_scenario = nullptr;
  CLI::App* cell_check = nullptr;
  CLI::App* replay = nullptr;
  CLI::App* serve = nullptr;
};

// The chain of a URDF model: one pair for every verb that takes a model file.
void AddLinkOptions(CLI::App* sub, ModelLinks* links) {
  sub->add_option("--base-link", links->base_link,
                  "URDF: link the arm starts at (default: the URDF's root link)");
  sub->add_option("--tip-link", links->tip_link,
                  "URDF: link the arm ends at, the end frame (default: the leaf link with the "
                  "most moving joints above it)");
}

// --cell and its credentials, and --record: where a verb's cell is (bench/runs/bench_cell.h).
void AddCellOptions(CLI::App* sub, CellOptions* cell) {
  sub->add_option("--cell", cell->address,
                  "drive the cell served at grpc://HOST:PORT (default: the scenario's twin, "
                  "in this process)");
  sub->add_option("--cell-ca", cell->tls_ca_file,
                  "TLS: CA certificate (PEM) of the served cell's certificate");
  sub->add_option("--cell-cert", cell->tls_cert_file, "TLS: client certificate (PEM)");
  sub->add_option("--cell-key", cell->tls_key_file, "TLS: the client certificate's key (PEM)");
  sub->add_option("--cell-token-file", cell->token_file,
                  "a file holding the served cell's bearer token");
  sub->add_option("--record", cell->record_dir,
                  "record every exchange with the cell into this new folder (`twinbench "
                  "replay` reruns it)");
}

// cell-check: the conformance battery of a served cell (remote/cell_check.h).
void AddCellCheckVerb(CLI::App* app, CliValues* v, Verbs* verbs) {
  remote::CellCheckOptions& o = v->cell_check;
  auto* sub = app->add_subcommand(
      "cell-check", "check that a served cell (grpc://HOST:PORT) keeps the cell protocol");
  verbs->cell_check = sub;
  sub->add_option("address", o.address, "the cell, grpc://HOST:PORT")->required();
  sub->add_option("--cell-ca", o.tls_ca_file,
                  "TLS: CA certificate (PEM) of the served cell's certificate");
  sub->add_option("--cell-cert", o.tls_cert_file, "TLS: client certificate (PEM)");
  sub->add_option("--cell-key", o.tls_key_file, "TLS: the client certificate's key (PEM)");
  sub->add_option("--cell-token-file", o.token_file,
                  "a file holding the served cell's bearer token");
  sub->add_flag("--allow-motion", o.allow_motion,
                "run the checks that move a robot (the cell must be clear); without it they "
                "are skipped");
  sub->add_option("--robot", o.robot, "the robot the motion checks move (default 0)")
      ->check(CLI::Range(0, 1));
  sub->add_option("--stop-move-rad", o.stop_move_rad,
                  "joint 1's move in the stop-on-disconnect check (default 1.0 rad)")
      ->check(CLI::Range(0.05, 3.0));
}

// serve-cell: a scenario's twin served over the cell protocol (bench/runs/serve_cell.h).
void AddServeVerb(CLI::App* app, CliValues* v, Verbs* verbs) {
  ServeCellOptions& o = v->serve_options;
  auto* serve = app->add_subcommand(
      "serve-cell", "serve a scenario's twin over the cell protocol (gRPC) until SIGINT/SIGTERM");
  verbs->serve = serve;
  serve->add_option("scenario", o.scenario, "scenario file")->required();
  serve->add_option("--listen", o.listen,
                    "HOST:PORT to listen on (port 0: a free one); beyond loopback needs TLS and "
                    "--client-ca or --token-file")
      ->required();
  serve->add_option("--trial", o.trial,
                    "study trial t: the scenario's truth seed + t, as `run --trial` (default 0)")
      ->check(CLI::Range(0, 1000000000));
  serve->add_option("--tls-cert", o.tls_cert_file, "TLS: server certificate (PEM)");
  serve->add_option("--tls-key", o.tls_key_file, "TLS: the server certificate's key (PEM)");
  serve->add_option("--client-ca", o.client_ca_file,
                    "TLS: require client certificates signed by this CA (PEM)");
  serve->add_option("--token-file", o.token_file,
                    "require the bearer token on this file's first line");
  serve->add_option("--heartbeat-timeout", o.heartbeat_timeout_s,
                    "seconds of silence after which a session ends and motion stops (default 2)")
      ->check(CLI::Range(0.01, 3600.0));
  serve->add_flag("--no-truth", "do not offer the twin's truth (TwinBench.Truth)");
  serve->add_flag("--realtime", o.realtime, "pace the simulation to wall-clock time");
}

// info, fk, ik, export-urdf and demo: a robot model's kinematics.
void AddKinematicsVerbs(CLI::App* app, CliValues* v, Verbs* verbs) {
  auto* info = app->add_subcommand("info", "print a robot model's parameters (mm, deg)");
  verbs->info = info;
  info->add_option("model", v->model, "model file (.yaml or .urdf)")->required();
  AddLinkOptions(info, &v->links);
  auto* fk = app->add_subcommand("fk", "forward kinematics of a model at joint angles");
  verbs->fk = fk;
  fk->add_option("model", v->model, "model file (.yaml or .urdf)")->required();
  AddLinkOptions(fk, &v->links);
  fk->add_option("--q", v->q, "joint angles in degrees, one per joint, comma-separated")
      ->required();
  auto* ik = app->add_subcommand("ik", "inverse kinematics of a model for an end-frame pose");
  verbs->ik = ik;
  ik->add_option("model", v->model, "model file (.yaml or .urdf)")->required();
  AddLinkOptions(ik, &v->links);
  ik->add_option("--xyz", v->xyz, "target position in mm, comma-separated")->required();
  ik->add_option("--rpy", v->rpy, "target roll,pitch,yaw in degrees (fixed axes)");
  ik->add_option("--seed", v->seed, "start joint angles in degrees (default: mid-range)");
  ik->add_flag("--position-only", v->position_only, "ignore the target orientation");
  auto* export_urdf = app->add_subcommand("export-urdf", "write a model as URDF");
  verbs->export_urdf = export_urdf;
  export_urdf->add_option("model", v->model, "model file (.yaml or .urdf)")->required();
  AddLinkOptions(export_urdf, &v->links);
  export_urdf->add_option("--out", v->out, "output URDF path")->required();
  auto* demo = app->add_subcommand("demo", "kinematic demo on the two Reinovo-like models");
  verbs->demo = demo;
  demo->add_option("--model-dir", v->model_dir, "folder with reinovo_r{1,2}.{yaml,urdf}");
  demo->add_option("--samples", v->samples, "random poses per robot")->check(CLI::Range(1, 100000));
  demo->add_option("--seed", v->rng_seed, "random seed");
}

// render, benchmark-twin, run and benchmark-planning: a scenario on the twin (or its planner).
void AddTwinVerbs(CLI::App* app, CliValues* v, Verbs* verbs) {
  auto* render = app->add_subcommand("render", "write PNGs of the hand camera and of the cell");
  verbs->render = render;
  render->add_option("scenario", v->render_options.scenario, "scenario file")->required();
  render->add_option("--out", v->render_options.out_dir, "output folder")->required();
  render->add_option("--poses", v->render_options.poses, "number of poses")
      ->check(CLI::Range(1, 20));
  auto* bench = app->add_subcommand("benchmark-twin", "time rendering and settled moves");
  verbs->bench = bench;
  bench->add_option("scenario", v->bench_options.scenario, "scenario file")->required();
  bench->add_option("--frames", v->bench_options.frames, "frames per figure")
      ->check(CLI::Range(1, 100000));
  bench->add_option("--moves", v->bench_options.moves, "settled moves")
      ->check(CLI::Range(2, 100000));

  auto* run = app->add_subcommand(
      "run", "run a scenario's calibration on the twin, score it against truth, write a report");
  verbs->run = run;
  run->add_option("scenario", v->run_options.scenario, "scenario file")->required();
  run->add_option("--out", v->run_options.out_dir, "output folder (replaced when complete)")
      ->required();
  run->add_flag("--quiet", v->run_options.quiet, "no progress lines");
  run->add_flag("--no-diagnosis", "skip model discovery after the calibration");
  run->add_option("--trial", v->run_options.trial,
                  "study trial t: the scenario's truth and estimator seeds + t (default 0)")
      ->check(CLI::Range(0, 1000000000));
  run->add_option("--plan-cache", v->run_options.plan_cache,
                  "folder of cached pose plans (plans once per planner input)");
  run->add_flag("--no-images", v->no_images, "write neither servo images nor report.html");
  run->add_option("--junit", v->run_options.junit,
                  "write the acceptance criteria's verdict as JUnit XML to this file");
  AddCellOptions(run, &v->run_options.cell);

  auto* bench_planning = app->add_subcommand(
      "benchmark-planning", "time the pose planning of a scenario's calibration (no twin)");
  verbs->bench_planning = bench_planning;
  bench_planning->add_option("scenario", v->planning_options.scenario, "scenario file")->required();
  bench_planning->add_option("--threads", v->planning_options.threads,
                             "planner threads (default: one per core)");
}

// replay: a recorded run (`run --record`) rerun from its recording, with no cell.
void AddReplayVerb(CLI::App* app, CliValues* v, Verbs* verbs) {
  auto* replay = app->add_subcommand(
      "replay", "rerun a recorded run's procedure and scoring from its recording (`run "
                "--record`), with no cell; writes the same report");
  verbs->replay = replay;
  replay->add_option("recording", v->replay_dir, "recording folder (`run --record`)")
      ->required();
  replay->add_option("--out", v->replay_out, "output folder (replaced when complete)")
      ->required();
  replay->add_flag("--quiet", v->replay_quiet, "no progress lines");
  replay->add_flag("--no-images", v->replay_no_images,
                   "write neither servo images nor report.html (a run recorded with "
                   "--no-images replays without them)");
}

// replay: the recorded scenario, trial and options, the cell a ReplayCell of the recording
// (bench/runs/replay_cell.h); every recorded exchange must be used.
int RunReplay(const CliValues& v) {
  const RecordingManifest m = ReadRecordingManifest(v.replay_dir);
  RunOptions o;
  o.scenario = m.scenario_path;
  o.scenario_text = m.scenario_text;
  o.scenario_dir = m.scenario_dir;
  o.out_dir = v.replay_out;
  o.quiet = v.replay_quiet;
  o.trial = m.trial;
  o.diagnosis = m.diagnosis;
  o.images = m.images && !v.replay_no_images;  // as recorded, or fewer
  o.cell.replay_dir = v.replay_dir;
  std::printf("twinbench replay: %s (%s, trial %d, recorded %s by twinbench %s%s)\n",
              v.replay_dir.c_str(), m.scenario_path.c_str(), m.trial, m.started_utc.c_str(),
              m.twinbench.c_str(), m.complete ? "" : "; partial: its run stopped midway");
  return RunCalibrationScenario(o);
}

// study and study-merge: Monte Carlo studies and their shards.
void AddStudyVerbs(CLI::App* app, CliValues* v, Verbs* verbs) {
  auto* study = app->add_subcommand(
      "study", "Monte Carlo study: trials of a scenario in parallel processes, resumable");
  verbs->study = study;
  study->add_option("scenario", v->study_options.scenario, "scenario file")->required();
  study->add_option("--trials", v->study_options.trials, "trials of the whole study")->required();
  study->add_option("--jobs", v->study_options.jobs,
                    "trial processes at a time (default: the CPUs available)");
  study->add_option("--shard", v->shard, "run trials I, I+N, I+2N, ... (I/N, default 0/1)");
  study->add_option("--out", v->study_options.out_dir, "study folder (rerun to resume)")
      ->required();
  study->add_option("--plan-cache", v->study_options.plan_cache,
                    "plan cache folder (default OUT/plans)");
  study->add_flag("--quiet", v->study_quiet, "no progress bar");
  auto* merge = app->add_subcommand(
      "study-merge", "merge study shards into trials.jsonl, summary.json and summary.html");
  verbs->merge = merge;
  merge->add_option("dirs", v->merge_options.dirs, "study folders (shards)")->required();
  merge->add_option("--out", v->merge_options.out_dir, "merged study folder")->required();
}

// check: a scenario validated as `run` would.
void AddCheckVerb(CLI::App* app, CliValues* v, Verbs* verbs) {
  auto* check = app->add_subcommand(
      "check", "validate a scenario as `run` would (sections, acceptance, the cell), run nothing");
  verbs->check = check;
  check->add_option("scenario", v->check_scenario, "scenario file")->required();
  verbs->schema = app->add_subcommand(
      "schema", "write the scenario format as a JSON Schema (schemas/scenario.schema.json)");
  verbs->schema->add_option("--out", v->schema_out, "file to write (default: stdout)");
}

// new-scenario: a commented scenario file for any arm (bench/scaffold/new_scenario.h).
void AddNewScenarioVerb(CLI::App* app, CliValues* v, Verbs* verbs) {
  NewScenarioOptions& o = v->new_scenario;
  auto* sub = app->add_subcommand(
      "new-scenario", "write a valid, commented scenario for an arm (bases from its reach, "
                      "initial joints by IK), checked as `check` checks; never overwrites");
  verbs->new_scenario = sub;
  sub->add_option("--robot", o.robot, "robot 1's model (.yaml or .urdf): the camera robot")
      ->required();
  AddLinkOptions(sub, &o.links);
  sub->add_option("--second", o.second,
                  "robot 2's model (default: the same as --robot; tracker: none, one robot)");
  sub->add_option("--procedure", o.procedure, "optical-axis, tracker or handclasp")->required();
  sub->add_option("--out", o.out, "the scenario file to write (must not exist)")->required();
}

// identify: a robot's parameters from optical-axis measurements or a tracker file.
void AddIdentifyVerb(CLI::App* app, CliValues* v, Verbs* verbs) {
  IdentifyOptions& identify_options = v->identify_options;
  TrackerIdentifyOptions& tracker_options = v->tracker_options;
  auto* identify = app->add_subcommand(
      "identify", "identify a robot's parameters from recorded measurements (no twin)");
  verbs->identify = identify;
  identify->add_option("--model", identify_options.model, "nominal model (.yaml/.urdf)")
      ->required();
  AddLinkOptions(identify, &v->links);
  identify->add_option("--measurements", identify_options.measurements, "measurements.csv")
      ->required();
  identify->add_option("--robot", identify_options.robot,
                       "rows of this robot (default: the first row's)");
  identify->add_option("--board-mount", identify_options.board_mount,
                       "board frame in the flange: x,y,z,roll,pitch,yaw [mm, deg] (default 0)");
  identify->add_option("--out", identify_options.out_dir, "output folder")->required();
  identify->add_option("--ignore-column", tracker_options.ignore_columns,
                       "tracker file: a column to drop (e.g. a constant torso axis merged into "
                       "the model's base); repeatable");
  identify->add_option("--validate", tracker_options.validate,
                       "tracker file: a second file held out as the region split");
  identify->add_option("--holdout", tracker_options.holdout_fraction,
                       "tracker file: the part of the points each split holds out (default 0.2)");
  identify->add_option("--seed", tracker_options.seed,
                       "tracker file: seed of the random split (default 1)");
  identify->add_option("--declare", tracker_options.declared_terms,
                       "tracker file: an error term the arm is known to have, "
                       "TYPE[:JOINT[:ORDERS]] (e.g. joint_compliance:2); repeatable");
  identify->add_flag("--no-diagnosis", "tracker file: skip model discovery");
  identify->add_option("--diagnosis-alpha", tracker_options.diagnosis_alpha,
                       "tracker file: level of the residual test and of each discovery step "
                       "(default 0.05)");
  identify->add_option("--diagnosis-min-gain", tracker_options.diagnosis_min_gain_percent,
                       "tracker file: smallest held-out gain worth a term [%] (default 5)");
  identify->add_option("--diagnosis-max-effects", tracker_options.diagnosis_max_effects,
                       "tracker file: at most this many effects added (default 10; the search "
                       "ends on its tests first)");
  identify->add_option("--diagnosis-folds", tracker_options.diagnosis_folds,
                       "tracker file: folds of the cross-validations (default 5)");
  identify->add_option("--encoder-sigma-deg", tracker_options.encoder_sigma_deg,
                       "tracker file: the joint readings' noise, carried into the diagnosis's "
                       "noise floor (default 0: the tracker's sigma alone)");
  identify->add_option("--jobs", tracker_options.jobs,
                       "tracker file: parallel candidate evaluations (default: the CPUs available)");
  identify->add_flag("--quiet", tracker_options.quiet, "no progress lines");
}

// synthesize-measurements and benchmark-kinematics: benchmarks of a model file (no twin).
void AddModelBenchmarkVerbs(CLI::App* app, CliValues* v, Verbs* verbs) {
  SynthesizeOptions& synth_options = v->synth_options;
  KinematicsBenchmarkOptions& kb_options = v->kb_options;
  auto* synth = app->add_subcommand(
      "synthesize-measurements",
      "write a synthetic optical-axis measurements.csv (benchmarks of `identify`)");
  verbs->synth = synth;
  synth->add_option("--model", synth_options.model, "nominal model (.yaml/.urdf)")->required();
  AddLinkOptions(synth, &v->links);
  synth->add_option("--rows", synth_options.rows, "measurement rows (15 to 1000000)");
  synth->add_option("--seed", synth_options.seed, "seed of the true geometry and the noise");
  synth->add_option("--out", synth_options.out, "output CSV")->required();

  auto* kbench = app->add_subcommand(
      "benchmark-kinematics",
      "time the kinematics: the analytic end-point Jacobian against autodiff, the iterative IK "
      "against the closed form of a spherical wrist");
  verbs->kbench = kbench;
  kbench->add_option("model", kb_options.model, "model file (.yaml or .urdf)")->required();
  AddLinkOptions(kbench, &v->links);
  kbench->add_option("--evaluations", kb_options.evaluations, "evaluations per figure");
}

// --record: a new folder (never one that exists, whatever it holds), outside --out and the
// inputs.
void ValidateRecordFolder(const std::string& record, const std::string& out_dir) {
  if (std::filesystem::exists(std::filesystem::symlink_status(record))) {
    throw InputError("--record", "'" + record + "' exists; a recording goes into a new folder "
                                 "(twinbench never writes into what it did not create)");
  }
  ValidateOutputFolder(record, "--record", "record", false);
  if (PathIsWithin(record, out_dir) || PathIsWithin(out_dir, record)) {
    throw InputError("--record", "'" + record + "' and --out '" + out_dir +
                                     "' overlap; name a recording folder beside the output "
                                     "folder");
  }
}

// The output-safety rule (bench/io/output_files.h): the verb marks the folders it writes
// and accepts only its own marks; the inputs named here are never written over, and every
// output path is checked before anything runs.
void CheckOutputsBeforeRun(const CLI::App& app, const Verbs& verbs, const CliValues& v) {
  const RunOptions& run_options = v.run_options;
  const StudyOptions& study_options = v.study_options;
  for (CLI::App* sub : app.get_subcommands()) SetOutputVerb(sub->get_name());
  for (const std::string* input :
       {&v.model, &v.render_options.scenario, &v.bench_options.scenario, &run_options.scenario,
        &v.planning_options.scenario, &study_options.scenario, &v.check_scenario,
        &v.identify_options.model, &v.identify_options.measurements,
        &v.tracker_options.validate, &v.synth_options.model, &v.kb_options.model,
        &v.new_scenario.robot, &v.new_scenario.second, &v.serve_options.scenario}) {
    NoteInput(*input);
  }
  for (const std::string& dir : v.merge_options.dirs) NoteInput(dir, true);
  if (*verbs.replay) NoteInput(v.replay_dir, true);
  const std::vector<std::pair<CLI::App*, const std::string*>> outputs = {
      {verbs.render, &v.render_options.out_dir}, {verbs.run, &run_options.out_dir},
      {verbs.identify, &v.identify_options.out_dir}, {verbs.merge, &v.merge_options.out_dir},
      {verbs.replay, &v.replay_out}};
  for (const auto& [sub, folder] : outputs) {
    if (*sub) ValidateOutputFolder(*folder, "--out");
  }
  if (*verbs.run && !run_options.cell.record_dir.empty()) {
    ValidateRecordFolder(run_options.cell.record_dir, run_options.out_dir);
  }
  if (*verbs.run && !run_options.junit.empty()) {
    ValidateJunitFile(run_options.junit, run_options.out_dir);
  }
  for (const auto& [sub, cache, out_dir] :
       {std::tuple{verbs.run, &run_options.plan_cache, &run_options.out_dir},
        std::tuple{verbs.study, &study_options.plan_cache, &study_options.out_dir}}) {
    if (!*sub || cache->empty()) continue;
    ValidateOutputFolder(*cache, "--plan-cache", "plan-cache", false);
    if (PathIsWithin(*cache, *out_dir) || PathIsWithin(*out_dir, *cache)) {
      throw InputError("--plan-cache", "'" + *cache + "' and --out '" + *out_dir +
                                           "' overlap; name a plan cache folder beside the "
                                           "output folder");
    }
  }
}

// identify: a tracker file (x_m / x_mm columns) goes to the tracker identification, anything
// else to the optical-axis identification; each refuses the other's options.
int RunIdentifyVerb(const CLI::App& identify, CliValues* v) {
  IdentifyOptions& identify_options = v->identify_options;
  TrackerIdentifyOptions& tracker_options = v->tracker_options;
  // A tracker file (x_m / x_mm columns) goes to the tracker identification.
  if (IsTrackerFile(identify_options.measurements)) {
    tracker_options.model = identify_options.model;
    tracker_options.links = v->links;
    tracker_options.measurements = identify_options.measurements;
    tracker_options.out_dir = identify_options.out_dir;
    tracker_options.diagnosis = identify.count("--no-diagnosis") == 0;
    if (!identify_options.board_mount.empty() || !identify_options.robot.empty()) {
      throw InputError("--board-mount/--robot", "options of optical-axis measurements; " +
                                                    identify_options.measurements +
                                                    " is a tracker file");
    }
    return RunTrackerIdentify(tracker_options);
  }
  if (!tracker_options.ignore_columns.empty() || !tracker_options.validate.empty() ||
      !tracker_options.declared_terms.empty() || identify.count("--no-diagnosis") > 0 ||
      identify.count("--diagnosis-alpha") + identify.count("--diagnosis-min-gain") +
              identify.count("--diagnosis-max-effects") +
              identify.count("--diagnosis-folds") + identify.count("--jobs") +
              identify.count("--encoder-sigma-deg") > 0) {
    throw InputError("--ignore-column/--validate/--declare/--diagnosis-*/--jobs",
                     "options of tracker files; " + identify_options.measurements +
                         " has no x_m/x_mm column");
  }
  identify_options.links = v->links;
  return RunIdentify(identify_options);
}

// Runs the verb given on the command line; kExitInternalError when none ran.
int RunVerb(const Verbs& verbs, CliValues* v) {
  if (*verbs.check) return CheckScenario(v->check_scenario);
  if (*verbs.schema) return RunSchemaVerb(v->schema_out);
  if (*verbs.info) return RunInfo(v->model, v->links);
  if (*verbs.fk) return RunFk(v->model, v->links, v->q);
  if (*verbs.ik) return RunIk(v->model, v->links, v->xyz, v->rpy, v->seed, v->position_only);
  if (*verbs.export_urdf) return RunExportUrdf(v->model, v->links, v->out);
  if (*verbs.demo) {
    return RunDemo(v->model_dir.empty() ? DataFile("models") : v->model_dir, v->samples,
                   v->rng_seed);
  }
  if (*verbs.render) return RunRender(v->render_options);
  if (*verbs.bench) return RunTwinBenchmark(v->bench_options);
  if (*verbs.serve) {
    v->serve_options.truth = verbs.serve->count("--no-truth") == 0;
    return RunServeCell(v->serve_options);
  }
  if (*verbs.run) {
    v->run_options.images = !v->no_images;
    v->run_options.diagnosis = verbs.run->count("--no-diagnosis") == 0;
    v->run_options.cell.record_info.twinbench =
        std::string(TWINBENCH_VERSION) + " (" + TWINBENCH_GIT_DESCRIBE + ")";
    return RunCalibrationScenario(v->run_options);
  }
  if (*verbs.study) {
    ParseShard(v->shard, &v->study_options.shard_index, &v->study_options.shard_count);
    v->study_options.progress = !v->study_quiet;
    return RunStudy(v->study_options);
  }
  if (*verbs.merge) return RunStudyMerge(v->merge_options);
  if (*verbs.replay) return RunReplay(*v);
  if (*verbs.new_scenario) return RunNewScenario(v->new_scenario);
  if (*verbs.cell_check) return remote::RunCellCheckVerb(v->cell_check);
  if (*verbs.bench_planning) return RunPlanningBenchmark(v->planning_options);
  if (*verbs.identify) return RunIdentifyVerb(*verbs.identify, v);
  if (*verbs.synth) {
    v->synth_options.links = v->links;
    return RunSynthesizeMeasurements(v->synth_options);
  }
  if (*verbs.kbench) {
    v->kb_options.links = v->links;
    return RunKinematicsBenchmark(v->kb_options);
  }
  return kExitInternalError;
}

}  // namespace
}  // namespace twin

int main(int argc, char** argv) {
  using namespace twin;
  // Before any thread exists: interrupts remove staging folders (bench/io/output_files.h), and
  // MuJoCo never writes MUJOCO_LOG.TXT into the current folder (its warnings and errors become
  // exceptions, reported on stderr).
  InstallInterruptCleanup();
  InstallMujocoErrorHandlers();
  // glibc's allocator keeps what is freed for reuse instead of handing it back to the system at
  // once (trimmed only above 256 MiB; mmap only for blocks of 64 MiB and more). The planner's
  // threads allocate and free their Jacobians and SVD work thousands of times a second; with
  // the defaults each round trip to the system cost page faults (benchmark-planning of
  // paper_reinovo.yaml: 13.0 s of system time in 54.5 s before, 0.2 s after; README.md of e5af83d,
  // "Speed of trials"). What a process holds at its peak stays with it until it exits.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  CLI::App app{"twinbench: digital-twin test bench for dual-robot kinematic calibration"};
  app.set_version_flag("--version", std::string("twinbench ") + TWINBENCH_VERSION + " (" +
                                        TWINBENCH_GIT_DESCRIBE + ")");
  app.require_subcommand(1);

  // The verbs and their options, in the order of --help.
  CliValues values;
  Verbs verbs;
  AddKinematicsVerbs(&app, &values, &verbs);
  AddTwinVerbs(&app, &values, &verbs);
  AddReplayVerb(&app, &values, &verbs);
  AddStudyVerbs(&app, &values, &verbs);
  AddCheckVerb(&app, &values, &verbs);
  AddNewScenarioVerb(&app, &values, &verbs);
  AddIdentifyVerb(&app, &values, &verbs);
  AddModelBenchmarkVerbs(&app, &values, &verbs);
  AddCellCheckVerb(&app, &values, &verbs);
  AddServeVerb(&app, &values, &verbs);
  std::string completion_shell;
  CLI::App* completion = AddCompletionVerb(&app, &completion_shell);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::fprintf(stderr, "error: command line: %s (see twinbench --help)\n", e.what());
    return kExitUserError;
  }
  if (*completion) {
    std::fputs(BashCompletion(app).c_str(), stdout);
    return 0;
  }
  try {
    // The GL back end's name is checked now; whether EGL can honour it, at the first render.
    GlChoiceFromEnvironment();
    // Every output path checked, every input noted, before anything runs.
    CheckOutputsBeforeRun(app, verbs, values);
    // The verb.
    return RunVerb(verbs, &values);
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitUserError;
  } catch (const std::filesystem::filesystem_error& e) {
    // Output paths that cannot be written (permissions, a full disk) are the user's to fix.
    std::fprintf(stderr, "error: %s: %s\n", e.path1().string().c_str(), e.code().message().c_str());
    return kExitUserError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return kExitInternalError;
  }
  return kExitInternalError;
}
