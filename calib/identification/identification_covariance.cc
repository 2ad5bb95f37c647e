#include "calib/identification/identification_covariance.h"

#include <cmath>

namespace twin {

IdentificationCovariance EstimateIdentificationCovariance(
    const KinematicModel& nominal, const std::vector<AxisSample>& samples,
    const NonlinearIdentificationResult& result) {
  IdentificationCovariance out;
  const IdentificationResult& e = result.engine;
  const int rank = result.observability.rank;
  if (result.status == NonlinearIdentificationStatus::kFailed || rank < 1 ||
      result.z.size() != rank || samples.empty() || e.covariance_z.rows() != rank) {
    out.reason = "the identification failed or identified nothing";
    return out;
  }
  out.redundancy = e.redundancy;
  if (out.redundancy < 1) {
    out.reason = "no redundancy (" + std::to_string(e.redundancy + e.unknowns) +
                 " independent residuals, " + std::to_string(e.unknowns) + " unknowns)";
    return out;
  }
  if (!e.covariance_z.allFinite() || !(e.covariance_z.diagonal().minCoeff() > 0.0)) {
    out.reason = "J^T J is singular";
    return out;
  }
  // The engine's covariance is already s^2 (J^T J)^-1 restricted to z; the perpendicular
  // group's sigma (1 / its weight) times sigma0 is s in metres.
  out.z = e.covariance_z;
  out.sigma_z = out.z.diagonal().cwiseSqrt();
  const int n = nominal.num_parameters();
  out.sigma_parameters = Eigen::VectorXd(n);
  for (int i = 0; i < n; ++i) out.sigma_parameters(i) = e.parameters[i].sigma;
  for (const GroupSummary& g : e.groups) {
    if (g.name == "perpendicular") out.residual_sigma = g.sigma * e.sigma0;
  }
  out.ok = true;
  return out;
}

}  // namespace twin
