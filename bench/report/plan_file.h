// A plan cache file (bench/runs/plan_cache.h) as a file format: one JSON object
// {"inputs": PlanInputsText, "plan": {...}} and a newline, every double of the plan a C99
// hex-float string so that a plan read back is bit-equal to the one stored.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "calib/planning/plan_store.h"

namespace twin {

/// A plan as JSON (doubles as C99 hex-float strings, so that a plan read back is bit-equal).
nlohmann::json PlanToJson(const PosePlanResult& plan);
/// The inverse of PlanToJson; throws InputError (naming `where`) for a malformed document.
PosePlanResult PlanFromJson(const nlohmann::json& j, const std::string& where);

/// The text of the plan file of `plan` for the planner inputs `inputs_text`.
std::string PlanFileText(const std::string& inputs_text, const PosePlanResult& plan);

/// The plan in the file at `path` when the file holds a plan for `inputs_text`; nullopt when
/// it is missing, unreadable, malformed or for other inputs (a miss, never an error).
std::optional<PosePlanResult> ReadPlanFile(const std::string& path,
                                           const std::string& inputs_text);

}  // namespace twin
