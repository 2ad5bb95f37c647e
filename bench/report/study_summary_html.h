// summary.html of a study: one self-contained page (inline CSS and SVG, no scripts) from
// summary.json (bench/report/study_summary.h) and the records it was computed from: the trial
// counts and failures, a histogram and an ECDF of each headline figure (truth errors after
// calibration, misaligned errors, intrinsics, base-frame errors, frames per pose: those the
// records have), the coverage check with how to read it, the per-parameter error distributions
// (p5-p95 bar and median per parameter) and the table of every figure.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace twin {

/// The page; any summary and records are accepted (missing parts are left out).
std::string RenderStudySummaryHtml(const nlohmann::json& summary,
                                   const std::vector<nlohmann::json>& records);

}  // namespace twin
