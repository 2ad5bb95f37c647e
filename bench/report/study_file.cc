#include "bench/report/study_file.h"

#include <exception>
#include <fstream>

#include <nlohmann/json.hpp>

#include "calib/common/errors.h"

namespace twin {
using json = nlohmann::json;

std::string StudyFileText(const StudyFile& s) {
  const json j = {{"scenario_file", s.scenario_file},
                  {"scenario", s.scenario},
                  {"scenario_hash", s.scenario_hash},
                  {"trials", s.trials},
                  {"shard", s.shard}};
  return j.dump(2) + "\n";
}

std::optional<StudyFileIdentity> ReadStudyFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  json j;
  try {
    j = json::parse(in);
  } catch (const std::exception& e) {
    throw InputError(path, std::string("not a study file: ") + e.what());
  }
  if (!j.is_object()) throw InputError(path, "not a study file: not a JSON object");
  StudyFileIdentity id;
  for (const auto& [key, value] : {std::pair{"scenario_hash", &id.scenario_hash},
                                   std::pair{"shard", &id.shard}}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_string()) throw InputError(path, std::string("not a study file: ") + key +
                                                        " is not a string");
    *value = j[key].get<std::string>();
  }
  return id;
}

}  // namespace twin
