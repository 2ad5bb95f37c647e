// `twinbench identify` on a laser-tracker file (bench/io/tracker_file.h): the identification
// with held-out scoring of calib/procedures/tracker_calibration.h, written as report.json and
// the identified model (docs/reference/file-formats.md, "Tracker files").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bench/io/model_loader.h"

namespace twin {

struct TrackerIdentifyOptions {
  std::string model;                        ///< nominal model (.yaml / .urdf), any joint count
  ModelLinks links;  ///< --base-link / --tip-link of a URDF model
  std::string measurements;                 ///< the tracker file
  std::vector<std::string> ignore_columns;  ///< columns to drop (e.g. a constant torso axis)
  std::string validate;                     ///< optional second file: the region split's part
  double holdout_fraction = 0.2;            ///< of each split
  std::uint64_t seed = 1;                   ///< of the random split
  std::string out_dir;                      ///< report.json, identified_<robot>.yaml
  /// Error terms the engineer knows the arm has (TYPE[:JOINT[:ORDERS]]), in the model from
  /// the start: their magnitudes are identified, discovery does not try them again.
  std::vector<std::string> declared_terms;
  bool diagnosis = true;                    ///< model discovery after the identification
  double diagnosis_alpha = 0.05;            ///< DiscoveryOptions::alpha
  double diagnosis_min_gain_percent = 5.0;  ///< DiscoveryOptions::min_gain_percent
  int diagnosis_max_effects = 10;           ///< DiscoveryOptions::max_effects
  int diagnosis_folds = 5;                  ///< DiscoveryOptions::folds
  double encoder_sigma_deg = 0.0;           ///< stated joint reading noise (DiscoveryOptions)
  int jobs = 0;                             ///< parallel candidate evaluations; 0: all cores
  bool quiet = false;                       ///< no progress lines
};

/// Runs it; returns 0. Throws InputError for bad input (nothing is written then).
int RunTrackerIdentify(const TrackerIdentifyOptions& options);

}  // namespace twin
