// One line of a study's trials.jsonl: a finished trial (`twinbench run --trial t` of the
// scenario) as one JSON object:
//   scenario_hash   ScenarioHash of the scenario (content of the scenario and model files)
//   scenario        the scenario's name
//   trial           t; seeds.{truth,estimator}: the seeds it ran with (the file's + t)
//   status          "ok" or "failed"; reason: why it failed (empty when ok); exit_code
//   figures         every number (and true/false) of its report.json, flattened to dotted
//                   keys: objects by key, arrays by index ("[3]") or, for items with a "name",
//                   by name ("robots.r2.parameters[r2.link3.alpha].estimated"); per-iteration
//                   traces (planning.fitness_history, the LM's eps_history_mm), the servo image
//                   list and the split candidates are left out; timing goes to `run`
//   labels          every string of the report, flattened the same way (methods, statuses)
//   run             how and where it ran, not what it found: wall_s, the report's timing_s
//                   and *time_s keys, from_plan_store flags; comparisons of studies leave it out
#pragma once

#include <optional>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "bench/io/scenario.h"

namespace twin {

/// The flattened parts of a report (see above).
struct FlatReport {
  nlohmann::json figures = nlohmann::json::object();
  nlohmann::json labels = nlohmann::json::object();
  nlohmann::json timing = nlohmann::json::object();
};

/// Flattens a report.json document (the top-level `scenario` key is left out).
FlatReport FlattenReport(const nlohmann::json& report);

/// A trial's report.json as the study reads it (another process' output).
struct TrialReport {
  bool failed = false;                ///< its "status" is "failed" (a run that reports failure)
  std::optional<std::string> reason;  ///< its "reason", when a string
  FlatReport flat;                    ///< its figures, labels and timing
};

/// Reads the report.json at `path`; nullopt when it is missing or not a JSON object.
std::optional<TrialReport> ReadTrialReport(const std::string& path);

/// What the study knows about one finished trial process.
struct TrialOutcome {
  std::string status;          ///< "ok" or "failed"
  std::string reason;          ///< why it failed; empty when ok
  int exit_code = 0;           ///< the process' exit code, or 128 + signal
  const TrialReport* report = nullptr;  ///< its report.json, when it wrote one
  double wall_s = 0.0;         ///< wall time of the process [s]
};

/// One line of trials.jsonl (see above), with what the study and the merge read of it typed.
class TrialRecord {
 public:
  TrialRecord() = default;
  /// A record as read or made; its "trial" must be an integer (ReadTrialsFile checks).
  explicit TrialRecord(nlohmann::json document) : document_(std::move(document)) {}

  /// The trial number.
  int trial() const;
  /// The scenario hash; nullopt when the record has none.
  std::optional<std::string> scenario_hash() const;
  /// True when the records are equal but for how they ran (ComparablePart).
  bool SameResultAs(const TrialRecord& other) const;
  /// The whole record (the study summary reads it).
  const nlohmann::json& document() const { return document_; }

 private:
  nlohmann::json document_;
};

/// The trials.jsonl line of trial `scenario.trial` (ApplyTrial already applied).
TrialRecord MakeTrialRecord(const std::string& scenario_hash, const Scenario& scenario,
                            const TrialOutcome& outcome);

/// The record without `run`: what must be equal when the same trial runs twice.
nlohmann::json ComparablePart(const nlohmann::json& record);

}  // namespace twin
