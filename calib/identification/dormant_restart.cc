#include "calib/identification/dormant_restart.h"

namespace twin {

bool KeepRestart(const IdentificationResult& first, const IdentificationResult& again) {
  return again.observability.rank > first.observability.rank &&
         again.cost_after <= (1.0 + kRestartCostSlack) * first.cost_after;
}

std::optional<RobotModel> WithDormantTermsWoken(const RobotModel& start,
                                                const IdentificationResult& first) {
  if (!HasDormantTermsAtZero(start)) return std::nullopt;
  return WithDormantTermsFrom(start, first.model);
}

}  // namespace twin
