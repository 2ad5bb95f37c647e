#include "bench/report/scenario_json.h"

namespace twin {

nlohmann::json ScenarioJson(const Scenario& sc) {
  return nlohmann::json{{"name", sc.name},
                        {"file", sc.path},
                        {"seed", sc.seeds.truth},
                        {"seeds", {{"truth", sc.seeds.truth}, {"estimator", sc.seeds.estimator}}},
                        {"trial", sc.trial}};
}

}  // namespace twin
