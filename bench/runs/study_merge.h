// `twinbench study-merge DIR... --out OUT`: joins the shards of a study (each DIR a `twinbench
// study` folder with trials.jsonl) into OUT/trials.jsonl (sorted by trial, each trial once),
// OUT/summary.json and OUT/summary.html (bench/report/study_summary.h). Refuses shards of
// different scenarios (their records' scenario hashes differ); a trial recorded in more than
// one folder is kept once (the first folder's record) and counted; if the copies differ in
// more than how they ran (bench/report/trial_record.h, ComparablePart), that is reported. OUT
// is written to OUT.partial and renamed into place when complete.
#pragma once

#include <string>
#include <vector>

namespace twin {

/// Options of RunStudyMerge.
struct StudyMergeOptions {
  std::vector<std::string> dirs;  ///< study folders (shards)
  std::string out_dir;            ///< the merged study folder (replaced when complete)
};

/// Merges (see above); prints what it merged. Returns 0. Throws InputError for a folder
/// without trials.jsonl, a malformed line, or different scenario hashes.
int RunStudyMerge(const StudyMergeOptions& options);

}  // namespace twin
