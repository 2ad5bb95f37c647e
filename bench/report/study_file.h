// A study folder's study.json (bench/runs/study_run.h): what the folder holds a study of, so
// that a rerun with another scenario or shard is refused. One JSON object:
//   scenario_file, scenario, scenario_hash, trials, shard ("I/N")
#pragma once

#include <optional>
#include <string>

namespace twin {

/// The content of study.json.
struct StudyFile {
  std::string scenario_file;  ///< the scenario file, absolute
  std::string scenario;       ///< its name
  std::string scenario_hash;  ///< ScenarioHash of it
  int trials = 0;             ///< trials of the whole study
  std::string shard;          ///< "I/N"
};

/// What a rerun checks of an existing study.json (absent keys: nullopt).
struct StudyFileIdentity {
  std::optional<std::string> scenario_hash;
  std::optional<std::string> shard;
};

/// study.json's text (keys in JSON order, two-space indent, newline).
std::string StudyFileText(const StudyFile& study);

/// Reads study.json at `path`; nullopt when there is none. Throws InputError naming the path
/// when it is not a JSON object with string scenario_hash and shard (where present).
std::optional<StudyFileIdentity> ReadStudyFile(const std::string& path);

}  // namespace twin
