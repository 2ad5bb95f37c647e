// `twinbench run` (the main job: a scenario's whole optical-axis calibration on the twin,
// scored against truth, written as a report) and `twinbench identify` (identification alone on
// recorded measurements, no twin: the path real data takes).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

#include "bench/io/measurements_csv.h"  // the limits of a measurements file
#include "bench/io/calibration_config.h"
#include "bench/io/model_loader.h"
#include "bench/io/scenario.h"
#include "bench/scoring/calibration_results.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/procedures/optical_axis_procedure.h"
#include "bench/runs/bench_cell.h"
#include "sim/cell/twin_cell.h"

namespace twin {

/// Options of RunCalibrationScenario.
struct RunOptions {
  std::string scenario;  ///< scenario file with a calibration: section
  std::string out_dir;   ///< output folder; replaced only once everything is written
  bool quiet = false;    ///< no progress lines
  int trial = 0;         ///< study trial: both scenario seeds + trial (ApplyTrial)
  /// Folder of the plan cache (PlanStore files keyed by the planner's inputs); empty: plan
  /// every time.
  std::string plan_cache;
  bool images = true;    ///< write servo_*.png and report.html (studies leave them out)
  std::string junit;     ///< JUnit XML of the acceptance criteria to write (empty: none)
  bool diagnosis = true; ///< model discovery after the calibration (--no-diagnosis)
  CellOptions cell;      ///< the cell to drive (--cell) and the recording (--record)
  /// Non-empty: the scenario's content (`twinbench replay`: the recorded scenario), read in
  /// place of the file `scenario` (which still names it), model paths relative to
  /// scenario_dir.
  std::string scenario_text;
  std::string scenario_dir;
};

/// The run's scenario (the file, or options.scenario_text), as trial options.trial; its text
/// into *text when given.
Scenario LoadRunScenario(const RunOptions& options, std::string* text = nullptr);

/// The run's cell options; with --record, what recording.json says of the run (the scenario
/// `sc` read from `text`, the trial, the options).
CellOptions RunCellOptions(const RunOptions& options, const Scenario& sc,
                           const std::string& text);

/// Runs the scenario and writes out_dir/report.json, measurements.csv, servo_*.png and
/// report.html; prints progress and a summary. Returns the exit code: 0, or 3 when the
/// scenario's acceptance criteria are missed (bench/report/acceptance.h). Throws InputError for
/// bad input and for a refused procedure, naming the scenario file (nothing is written then).
int RunCalibrationScenario(const RunOptions& options);

/// The run options that reach the optical-axis calibration's config (in a plain run and in the
/// dual-arm workflow alike): --no-diagnosis, --plan-cache, and images (studies leave them out).
void ApplyRunOptions(const RunOptions& options, CalibrationConfig* config);

/// One optical-axis stage on an existing cell (also a step of the dual-arm workflow): runs the
/// procedure with `config`, scores it against the cell's truth and writes servo_*.png,
/// measurements.csv and identified_<robot>.yaml into `staging`; returns the typed results
/// (bench/scoring/calibration_results.h; bench/report/calibration_report.h writes them).
/// Progress lines carry the time since t_start. With config.diagnosis.enabled, model discovery
/// runs on each calibrated robot's aligned poses (estimator side, before any truth is read)
/// into robots[i].diagnosis; otherwise that says why it was skipped. The physical truth is
/// left to the caller (robots[i].physical* stay empty).
CalibrationStageResult RunCalibrationStage(BenchCell& cell, const Scenario& scenario,
                                           CalibrationConfig config,
                                           const std::filesystem::path& staging, bool quiet,
                                           std::chrono::steady_clock::time_point t_start);

/// Options of RunIdentify.
struct IdentifyOptions {
  std::string model;          ///< nominal model file (.yaml/.urdf) of the calibrated robot
  ModelLinks links;  ///< --base-link / --tip-link of a URDF model
  std::string measurements;   ///< measurements.csv as `twinbench run` writes it
  std::string robot;          ///< rows of this robot (default: the model's... the only one)
  std::string board_mount;    ///< "x,y,z,roll,pitch,yaw" in mm and deg (X_FT); default 0s
  std::string out_dir;        ///< output folder (identification.json, identified model)
};


/// Validates a scenario as `twinbench run` would before running (the scenario, its procedure
/// sections, acceptance, and the twin cell built at its initial pose), runs nothing and
/// writes nothing. Prints what it would run. Returns 0; throws InputError.
int CheckScenario(const std::string& scenario_path);

/// Identifies the robot from recorded rows (calibration / validation sets from the CSV's set
/// column) with both methods; writes the identified model and a JSON summary. Returns the exit
/// code; throws InputError for bad input.
int RunIdentify(const IdentifyOptions& options);

}  // namespace twin
