#include "bench/runs/study_merge.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>

#include "bench/io/model_loader.h"
#include "bench/report/study_summary_files.h"
#include "bench/report/trial_record.h"
#include "bench/report/trial_records_file.h"
#include "calib/common/errors.h"

namespace twin {
namespace fs = std::filesystem;

int RunStudyMerge(const StudyMergeOptions& o) {
  if (o.dirs.empty()) throw InputError("study-merge", "expected one or more study folders");
  if (o.out_dir.empty()) throw InputError("--out", "expected a folder");
  std::map<int, TrialRecord> by_trial;
  std::string hash, hash_from;
  int duplicates = 0, conflicts = 0, read = 0;
  for (const std::string& dir : o.dirs) {
    const std::string path = (fs::path(dir) / "trials.jsonl").string();
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (fs::exists(st) && !fs::is_regular_file(st)) {
      throw InputError(path, "not a regular file (a FIFO, socket or device could block or never "
                             "end); a study writes trials.jsonl as a file");
    }
    if (!fs::exists(st)) {
      if (fs::is_regular_file(fs::path(dir) / "study.json")) continue;  // nothing recorded yet
      throw InputError(dir, "not a study folder (no trials.jsonl or study.json)");
    }
    TrialsFileContent content = ReadTrialsFile(path);
    for (TrialRecord& r : content.records) {
      ++read;
      const std::string h = r.scenario_hash().value_or("");
      if (hash.empty()) {
        hash = h;
        hash_from = dir;
      } else if (h != hash) {
        throw InputError(path, "trial " + std::to_string(r.trial()) + " is of scenario hash " + h +
                                   ", but " + hash_from + " holds " + hash +
                                   ": shards of different scenarios cannot be merged");
      }
      const int t = r.trial();
      const auto it = by_trial.find(t);
      if (it == by_trial.end()) {
        by_trial.emplace(t, std::move(r));
        continue;
      }
      ++duplicates;
      if (!it->second.SameResultAs(r)) {
        ++conflicts;
        std::fprintf(stderr, "study-merge: trial %d differs between two folders (kept the "
                     "first; second in %s)\n", t, dir.c_str());
      }
    }
  }
  std::vector<TrialRecord> records;
  for (auto& [t, r] : by_trial) records.push_back(std::move(r));
  const std::string staging = CreateStagingDirectory(o.out_dir);
  try {
    WriteTrialsFile((fs::path(staging) / "trials.jsonl").string(), records);
    const StudySummaryCounts counts = WriteStudySummaryFiles(staging, records);
    PublishDirectory(staging, o.out_dir);
    if (!counts.mixed_renderers_warning.empty()) {
      std::fprintf(stderr, "%s\n", counts.mixed_renderers_warning.c_str());
    }
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    throw;
  }
  std::printf("study-merge: %d records from %zu folders: %zu trials (%d duplicates dropped, %d "
              "of them different), scenario hash %s; wrote %s/{trials.jsonl, summary.json, "
              "summary.html}\n",
              read, o.dirs.size(), records.size(), duplicates, conflicts, hash.c_str(),
              o.out_dir.c_str());
  return 0;
}

}  // namespace twin
