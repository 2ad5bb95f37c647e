#include "bench/report/scenario_json.h"

namespace twin {

nlohmann::json SeedsJson(const ScenarioSeeds& seeds) {
  nlohmann::json j = {{"truth", seeds.truth}, {"estimator", seeds.estimator}};
  if (seeds.noise) j["noise"] = *seeds.noise;
  return j;
}

nlohmann::json ScenarioJson(const Scenario& sc) {
  return nlohmann::json{{"name", sc.name},
                        {"file", sc.path},
                        {"seed", sc.seeds.truth},
                        {"seeds", SeedsJson(sc.seeds)},
                        {"trial", sc.trial}};
}

}  // namespace twin
