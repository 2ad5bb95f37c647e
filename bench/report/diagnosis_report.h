// The `diagnosis` section of a report (model discovery, calib/diagnosis/model_discovery.h),
// shared by `twinbench identify` on tracker files and the twin's tracker runs. Every key is in
// docs/explanation/discovery-statistics.md. Lengths in mm, angles in deg, other units as the term
// states.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "calib/diagnosis/model_discovery.h"

namespace twin {

/// {verdict, reason, noise_floor_mm, noise_floor, residual_test, heldout_rms_mm, region_rule,
///  steps[], effects_added[], candidates[], unexplained_evidence[], residual_maps[], session,
///  black_box}.
nlohmann::json DiagnosisJson(const DiscoveryResult& r);

/// A second-session score (session_scoring.h): {rms_mm (mean over the halvings), rms_sd_mm,
/// rms_min_mm, rms_max_mm, halvings}.
nlohmann::json SessionScoreJson(const SessionScore& s);

/// An HTML fragment (a section, no page) of DiagnosisJson's output: the verdict and reason, the
/// noise floor and residual tests, before/after bars of the region-disjoint held-out RMS, the
/// decision chain with every candidate, the strongest residual correlations and the residual
/// maps as small inline SVG charts. `d` without a verdict (skipped) gives a one-line note.
std::string DiagnosisHtml(const nlohmann::json& d);

/// Lines for the terminal: the verdict and the decision chain, one step a line
/// (DiscoveryResult::BriefReport, the one text of them).
std::string DiagnosisSummary(const DiscoveryResult& r);

}  // namespace twin
