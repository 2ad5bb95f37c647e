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
  const nlohmann::json& renderers = summary["renderers"];
  if (renderers.size() > 1) {
    std::string list;
    for (const auto& [name, n] : renderers.items()) {
      list += (list.empty() ? "" : "; ") + name + ": " + std::to_string(n.get<int>()) + " trials";
    }
    counts.mixed_renderers_warning =
        "warning: the trials rendered with " + std::to_string(renderers.size()) +
        " GL back ends (" + list + "); their figures mix two rasterisers' images. Set "
        "TWINBENCH_GL the same for every trial (docs/how-to/render-on-a-gpu.md)";
  }
  return counts;
}

}  // namespace twin
