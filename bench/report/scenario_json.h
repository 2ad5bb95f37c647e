// The report's `scenario` key, shared by every report of a run (calibration, tracker, handclasp,
// workflow): which scenario ran, from which file, with which seeds and trial.
#pragma once

#include <nlohmann/json.hpp>

#include "bench/io/scenario.h"

namespace twin {

/// The report's `scenario` key: name, file, seed (the truth seed, as before the split),
/// seeds.{truth,estimator[,noise]} and trial.
nlohmann::json ScenarioJson(const Scenario& scenario);

/// {truth, estimator} and, where the scenario sets it, noise.
nlohmann::json SeedsJson(const ScenarioSeeds& seeds);

}  // namespace twin
