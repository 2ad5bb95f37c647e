#include "bench/report/study_summary_files.h"

#include <filesystem>

#include <nlohmann/json.hpp>

#include "bench/io/model_loader.h"
#include "bench/report/study_summary.h"
#include "bench/report/study_summary_html.h"

namespace twin {

StudySummaryCounts WriteStudySummaryFiles(const std::string& dir,
                                          const std::vector<TrialRecord>& records) {
  const std::filesystem::path out(dir);
  std::vector<nlohmann::json> documents;
  documents.reserve(records.size());
  for (const TrialRecord& r : records) documents.push_back(r.document());
  const nlohmann::json summary = SummarizeStudy(documents);
  WriteFileAtomically((out / "summary.json").string(), summary.dump(2) + "\n");
  WriteFileAtomically((out / "summary.html").string(), RenderStudySummaryHtml(summary, documents));
  StudySummaryCounts counts;
  counts.failed = summary["trials"]["failed"].get<int>();
  return counts;
}

}  // namespace twin
