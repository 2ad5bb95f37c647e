// The report of `twinbench identify` on a laser-tracker file (bench/runs/
// tracker_identify_run.h): report.json and report.html from the identification's typed
// result. Keys of report.json (nlohmann's object sorts them when written):
//   file, model, robot, points, distinct_poses, rank_causes
//   columns                 joints, sigma, time, temperature, ignored[] {name, min, max}
//   heldout.<split>         rule, training_poses, before, after, training_after, worse
//   heldout.session         rule, points, halvings, nominal, geometric, discovered (each
//                           {rms_mm, rms_sd_mm, rms_min_mm, rms_max_mm, halvings}); null
//                           without --validate, discovered null with --no-diagnosis
//   all_points              before, after (fitted, not held out)
//   parameters[]            name, unit, nominal, estimated, correction, sigma
//   unidentifiable, condition_number, rank, sigma0, correlations[] {a, b, rho}
//   tracker_pose            xyz_mm, rotation_deg, rotation_axis
//   declared_terms, diagnosis (bench/report/diagnosis_report.h, or {verdict: null, skipped}),
//   warnings (the calibration's, then the diagnosis's)
#pragma once

#include <string>
#include <vector>

#include "bench/io/tracker_file.h"
#include "calib/diagnosis/model_discovery.h"
#include "calib/procedures/tracker_calibration.h"

namespace twin {

/// Everything the report of `identify` on a tracker file is made of; the pointers outlive
/// the report's making.
struct TrackerIdentifyResult {
  std::string file;                                    ///< the measurements file, as given
  std::string model;                                   ///< the model file, as given
  std::string robot;                                   ///< the model's name
  const TrackerFile* measurements = nullptr;           ///< the file as read
  std::vector<std::string> rank_causes;                ///< what lowers the rank, named
  const TrackerCalibrationResult* calibration = nullptr;  ///< with held-out scoring
  std::vector<std::string> declared_terms;             ///< the starting model's terms (labels)
  const DiscoveryResult* diagnosis = nullptr;          ///< null with --no-diagnosis
};

/// The report's texts.
struct TrackerIdentifyReport {
  std::string json_text;  ///< report.json (two-space indent, newline)
  std::string html;       ///< report.html
};

/// The report of `result`.
TrackerIdentifyReport MakeTrackerIdentifyReport(const TrackerIdentifyResult& result);

}  // namespace twin
