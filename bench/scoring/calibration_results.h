// Typed results of an optical-axis calibration stage on the twin (bench/runs/calibration_run.h):
// the procedure's outcome, model discovery per robot, and the bench's scores against the twin's
// truth, with where the time went. bench/report/calibration_report.h writes them as report.json;
// the console summary and the dual-arm workflow read them directly.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bench/scoring/calibration_scoring.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/procedures/optical_axis_procedure.h"

namespace twin {

/// A figure written into the output folder and its caption.
struct ReportImage {
  std::string file;     ///< file name in the output folder
  std::string caption;
};

/// Truth errors over the joint box of the poses the delivered model was fitted on.
struct CoveredRegionScore {
  std::size_t poses = 0;  ///< the poses that span the box
  JointBox box;
  RegionScore score;
};

/// The physical truth at seeded random poses (the twin's physics, every effect) against the
/// delivered and the discovered model at the same readings.
struct PhysicalTruthScore {
  std::size_t poses = 0;  ///< poses measured
  std::string rule;       ///< how the poses were chosen, for the report
  GaugeErrors calibrated, discovered;  ///< raw and rigid gauges (similarity not computed)
};

/// The visual servo's figures over a robot's aligned poses.
struct ServoFigures {
  int frames = 0;                 ///< frames grabbed, all aligned poses together
  int region_frames = 0;          ///< of them, region-of-interest frames
  int full_frame_fallbacks = 0;   ///< region frames that fell back to a full frame
  double max_final_pixel_error_px = 0.0;  ///< largest |du| or |dv| after the servo
};

/// Model discovery's outcome for one robot.
struct RobotDiagnosisResult {
  std::optional<DiscoveryResult> result;    ///< when it ran
  std::string skipped;                      ///< why not, when it did not
  std::vector<std::string> declared_terms;  ///< labels of the declared effects' terms
};

/// One calibrated robot's scores (bench side), beside its RobotCalibration.
struct RobotStageResult {
  std::string name;          ///< the robot's scenario name
  std::string camera_robot;  ///< the name of the robot that held the camera
  ObservabilityReport observability;  ///< of the delivered model's identification
  RobotScore score;                   ///< nominal and delivered model against truth
  std::optional<CoveredRegionScore> covered_region;  ///< when poses were used
  std::optional<RobotScore> calibration_set_model;   ///< with a refit: the held-out model
  ServoFigures servo;
  std::vector<ReportImage> images;                   ///< servo images written
  RobotDiagnosisResult diagnosis;
  /// Physical truth (after the diagnosis; only robots whose diagnosis ran): why it was
  /// skipped, or the whole joint space and the covered region (when >= 10 poses settled).
  std::optional<std::string> physical_skipped;
  std::optional<PhysicalTruthScore> physical, physical_covered_region;
};

/// Where a calibration stage's time went [s], and the cell's frames and moves.
struct CalibrationTiming {
  double total = 0, intrinsics = 0, intrinsics_detection = 0, intrinsics_zhang = 0;
  double planning = 0, planning_compute = 0, servoing = 0, identification = 0;
  double diagnosis = 0, scoring = 0;
  int frames = 0, region_frames = 0, moves = 0;
  double region_pixels = 0;  ///< pixels of all region frames
  double grab_image = 0, move_to = 0;
  /// The GL back end this process rendered with (GlBackendDescription); "" where it rendered
  /// nothing (a remote or replayed cell).
  std::string renderer;
};

/// The decrease of eq. 46's misaligned error by the calibration [%]; NaN without a before.
inline double DecreasePercent(double before, double after) {
  return before > 0.0 ? 100.0 * (before - after) / before
                      : std::numeric_limits<double>::quiet_NaN();
}

/// One optical-axis calibration stage, scored.
struct CalibrationStageResult {
  OpticalAxisResult procedure;  ///< what calib delivered
  /// False on a cell without truth (a real cell): every figure against truth is NaN (null in
  /// the report), the covered region, calibration-set model and physical truth left out.
  bool truth_available = true;
  /// robots[i] scores procedure.robots[i].
  std::vector<RobotStageResult> robots;
  PinholeIntrinsics true_intrinsics;  ///< the twin camera's truth
  DistortionCoefficients true_distortion;
  BoardGeometry plate;            ///< the printed plate Zhang's method saw
  bool dedicated_target = false;  ///< the plate is a dedicated intrinsics target
  PosePlannerOptions planner;     ///< the planner's options (positions per axis, run rule)
  double servo_tolerance_px = 0;  ///< the visual servo's tolerance
  CalibrationTiming timing;
};

}  // namespace twin
