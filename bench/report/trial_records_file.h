// A study's trials.jsonl on disk: one JSON object per line (bench/report/trial_record.h), each
// appended with one write(2) of the whole line and flushed to the disk (fsync) before the next
// trial is recorded, so that a study killed at any moment leaves every finished trial and at
// most one torn last line, which reading drops.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "bench/report/trial_record.h"

namespace twin {

/// What ReadTrialsFile found.
struct TrialsFileContent {
  std::vector<TrialRecord> records;  ///< the complete lines, in file order
  std::size_t valid_bytes = 0;       ///< length of the file up to the last complete line
  bool torn_tail = false;            ///< a last line without its newline was dropped
};

/// Reads `path` (a missing file is empty). A last line without a newline (a writer killed
/// mid-line) is dropped; any other line that is not a JSON object with an integer "trial" is
/// an InputError naming path:line.
TrialsFileContent ReadTrialsFile(const std::string& path);

/// Cuts `path` to `size` bytes (dropping a torn last line before appending). Throws
/// InputError naming the path on failure.
void TruncateTrialsFile(const std::string& path, std::size_t size);

/// Appends `record` as one line and flushes it to the disk. Throws InputError naming the path
/// on failure.
void AppendTrialRecord(const std::string& path, const TrialRecord& record);

/// Writes `records` as a new trials file at `path` atomically (merges).
void WriteTrialsFile(const std::string& path, const std::vector<TrialRecord>& records);

}  // namespace twin
