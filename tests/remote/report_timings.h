// What differs between two runs of one scenario on one twin, live, served or replayed: the
// wall-clock times. Shared by the remote tests that compare reports.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace twin {

// report.json less what is wall-clock time and so differs between any two runs, live or
// replayed: `timing_s` (every stage's seconds; the cell's frame and move counts stay), and
// per robot the stages' `time_s` / `wait_time_s` (identification, planning, servo). Everything
// else must be equal exactly (doubles bit for bit: nlohmann reads the shortest round-trip
// printing back to the same double).
inline nlohmann::json ReportWithoutTimings(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  nlohmann::json report = nlohmann::json::parse(text.str());
  if (report.contains("timing_s")) {
    nlohmann::json& t = report["timing_s"];
    nlohmann::json kept = nlohmann::json::object();
    if (t.contains("cell")) {
      for (const char* count : {"frames", "region_frames", "region_mean_pixels", "moves"}) {
        if (t["cell"].contains(count)) kept[count] = t["cell"][count];
      }
    }
    t = kept;
  }
  if (report.contains("robots")) {
    for (auto& [name, robot] : report["robots"].items()) {
      for (const char* stage : {"identification", "planning", "servo"}) {
        if (!robot.contains(stage)) continue;
        robot[stage].erase("time_s");
        robot[stage].erase("wait_time_s");
      }
    }
  }
  return report;
}

}  // namespace twin
