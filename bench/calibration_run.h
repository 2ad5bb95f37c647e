// `twinbench run` (the main job: a scenario's whole optical-axis calibration on the twin,
// scored against truth, written as a report) and `twinbench identify` (identification alone on
// recorded measurements, no twin: the path real data takes).
#pragma once

#include <string>

namespace twin {

/// Options of RunCalibrationScenario.
struct RunOptions {
  std::string scenario;  ///< scenario file with a calibration: section
  std::string out_dir;   ///< output folder; replaced only once everything is written
  bool quiet = false;    ///< no progress lines
};

/// Runs the scenario and writes out_dir/report.json, measurements.csv, servo_*.png and
/// report.html; prints progress and a summary. Returns the exit code. Throws InputError for bad
/// input (nothing is written then).
int RunCalibrationScenario(const RunOptions& options);

/// Options of RunIdentify.
struct IdentifyOptions {
  std::string model;          ///< nominal model file (.yaml/.urdf) of the calibrated robot
  std::string measurements;   ///< measurements.csv as `twinbench run` writes it
  std::string robot;          ///< rows of this robot (default: the model's... the only one)
  std::string board_mount;    ///< "x,y,z,roll,pitch,yaw" in mm and deg (X_FT); default 0s
  std::string out_dir;        ///< output folder (identification.json, identified model)
};

/// Identifies the robot from recorded rows (calibration / validation sets from the CSV's set
/// column) with both methods; writes the identified model and a JSON summary. Returns the exit
/// code; throws InputError for bad input.
int RunIdentify(const IdentifyOptions& options);

}  // namespace twin
