#include "bench/report/trial_record.h"

#include <exception>
#include <fstream>
#include <set>

#include "bench/report/scenario_json.h"

namespace twin {
namespace {

using json = nlohmann::json;

// Per-iteration traces and lists that are not figures of the result.
const std::set<std::string> kLeftOut = {"fitness_history", "eps_history_mm", "images",
                                        "candidates", "screened"};

bool IsTiming(const std::string& key) {
  return key == "timing_s" || key == "time_s" || key == "from_plan_store" ||
         (key.size() > 7 && key.compare(key.size() - 7, 7, "_time_s") == 0);
}

void Flatten(const json& j, const std::string& path, bool timing, FlatReport* out) {
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      if (kLeftOut.count(key)) continue;
      Flatten(value, path.empty() ? key : path + "." + key, timing || IsTiming(key), out);
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      const json& item = j[i];
      const bool named = item.is_object() && item.contains("name") && item["name"].is_string();
      const std::string index = named ? item["name"].get<std::string>() : std::to_string(i);
      Flatten(item, path + "[" + index + "]", timing, out);
    }
  } else if (j.is_number() || j.is_boolean()) {
    (timing ? out->timing : out->figures)[path] = j;
  } else if (j.is_string()) {
    (timing ? out->timing : out->labels)[path] = j;
  }
  // null: not available, left out
}

}  // namespace

FlatReport FlattenReport(const json& report) {
  FlatReport out;
  if (!report.is_object()) return out;
  for (const auto& [key, value] : report.items()) {
    if (key == "scenario" || kLeftOut.count(key)) continue;
    Flatten(value, key, IsTiming(key), &out);
  }
  return out;
}

std::optional<TrialReport> ReadTrialReport(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  json j;
  try {
    j = json::parse(in);
  } catch (const std::exception&) {
    return std::nullopt;  // torn or foreign: no report
  }
  if (!j.is_object()) return std::nullopt;
  TrialReport report;
  report.failed = j.contains("status") && j["status"].is_string() && j["status"] == "failed";
  if (j.contains("reason") && j["reason"].is_string()) report.reason = j["reason"];
  report.flat = FlattenReport(j);
  return report;
}

TrialRecord MakeTrialRecord(const std::string& scenario_hash, const Scenario& sc,
                            const TrialOutcome& o) {
  json r;
  r["scenario_hash"] = scenario_hash;
  r["scenario"] = sc.name;
  r["trial"] = sc.trial;
  r["seeds"] = SeedsJson(sc.seeds);
  r["status"] = o.status;
  r["reason"] = o.reason;
  r["exit_code"] = o.exit_code;
  FlatReport flat;
  if (o.report) flat = o.report->flat;
  r["figures"] = std::move(flat.figures);
  r["labels"] = std::move(flat.labels);
  json run = {{"wall_s", o.wall_s}};
  run["timing"] = std::move(flat.timing);
  r["run"] = std::move(run);
  return TrialRecord(std::move(r));
}

json ComparablePart(const json& record) {
  json c = record;
  c.erase("run");
  return c;
}

int TrialRecord::trial() const { return document_.at("trial").get<int>(); }

std::optional<std::string> TrialRecord::scenario_hash() const {
  if (!document_.contains("scenario_hash")) return std::nullopt;
  return document_["scenario_hash"].get<std::string>();
}

bool TrialRecord::SameResultAs(const TrialRecord& other) const {
  return ComparablePart(document_) == ComparablePart(other.document_);
}

}  // namespace twin
