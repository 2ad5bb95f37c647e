#include "bench/report/output_mark.h"

#include <exception>

#include <nlohmann/json.hpp>

namespace twin {

std::string OutputMarkText(const std::string& verb) {
  const nlohmann::json j = {{"written_by", "twinbench"}, {"verb", verb}};
  return j.dump() + "\n";
}

std::string OutputMarkVerb(const std::string& text) {
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (j.is_object() && j.value("written_by", "") == "twinbench" && j.contains("verb") &&
        j["verb"].is_string()) {
      return j["verb"].get<std::string>();
    }
  } catch (const std::exception&) {
    // Not JSON, or a written_by that is not a string: not our mark.
  }
  return "";
}

}  // namespace twin
