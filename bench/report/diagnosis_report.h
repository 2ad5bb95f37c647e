// The `diagnosis` section of a report (model discovery, calib/diagnosis/model_discovery.h),
// shared by `twinbench identify` on tracker files and the twin's tracker runs. Every key is in
// the README ("Model discovery"). Lengths in mm, angles in deg, other units as the term states.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "calib/diagnosis/model_discovery.h"

namespace twin {

/// {verdict, reason, noise_floor_mm, noise_floor, residual_test, heldout_rms_mm, region_rule,
///  steps[], effects_added[], candidates[], unexplained_evidence[], residual_maps[]}.
nlohmann::json DiagnosisJson(const DiscoveryResult& r);

/// Lines for the terminal: the verdict and the decision chain, one step a line.
std::string DiagnosisSummary(const DiscoveryResult& r);

}  // namespace twin
