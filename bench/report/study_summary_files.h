// The summary files of a study folder: summary.json (bench/report/study_summary.h) and
// summary.html (bench/report/study_summary_html.h) of the records of its trials.jsonl.
#pragma once

#include <string>
#include <vector>

#include "bench/report/trial_record.h"

namespace twin {

/// What the closing lines of `study` and `study-merge` print of the summary.
struct StudySummaryCounts {
  int failed = 0;  ///< failed trials among the records
  /// A line for stderr where the trials rendered with more than one GL back end (their figures
  /// mix two rasterisers' images); empty otherwise.
  std::string mixed_renderers_warning;
};

/// Writes `dir`/summary.json and `dir`/summary.html of `records`, each atomically (json first).
StudySummaryCounts WriteStudySummaryFiles(const std::string& dir,
                                          const std::vector<TrialRecord>& records);

}  // namespace twin
