#include "calib/diagnosis/evidence.h"

#include <algorithm>
#include <cmath>

#include "calib/common/errors.h"
#include "calib/diagnosis/statistics.h"

namespace twin::discovery {

std::vector<Quantity> Quantities(const RobotModel& model, const Data& data) {
  std::vector<Quantity> out;
  const int n = model.chain.num_joints();
  const int units = data.size();
  for (int j = 0; j < n; ++j) {
    Quantity q{"q" + std::to_string(j + 1), "rad", {}};
    for (int i = 0; i < units; ++i) q.values.push_back(data.context(i).q(j));
    out.push_back(q);
  }
  std::vector<Eigen::VectorXd> tau;
  for (int i = 0; i < units; ++i) tau.push_back(GravityTorques(model, data.context(i).q));
  for (int j = 0; j < n; ++j) {
    Quantity q{"tau" + std::to_string(j + 1), "N m", {}};
    for (const Eigen::VectorXd& t : tau) q.values.push_back(t(j));
    out.push_back(q);
  }
  Quantity order{"order", "row", {}};
  for (int i = 0; i < units; ++i) order.values.push_back(data.Order(i));
  out.push_back(order);
  bool time = true, temperature = true;
  for (int i = 0; i < units; ++i) {
    time = time && data.context(i).has_time();
    temperature = temperature && data.context(i).has_temperature();
  }
  if (time) {
    Quantity q{"time", "s", {}};
    for (int i = 0; i < units; ++i) q.values.push_back(data.context(i).time_s);
    out.push_back(q);
  }
  if (temperature) {
    Quantity q{"temperature", "K", {}};
    for (int i = 0; i < units; ++i) q.values.push_back(data.context(i).temperature_delta_K);
    out.push_back(q);
  }
  return out;
}

std::vector<ResidualCorrelation> StrongestCorrelations(const std::vector<Quantity>& quantities,
                                                       const Components& components,
                                                       int keep) {
  std::vector<ResidualCorrelation> out;
  for (const Quantity& q : quantities) {
    for (const auto& [name, values] : components) {
      out.push_back({q.name, name, stats::Correlation(q.values, values)});
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const ResidualCorrelation& a, const ResidualCorrelation& b) {
                     return std::abs(a.r) > std::abs(b.r);
                   });
  if (static_cast<int>(out.size()) > keep) out.resize(keep);
  return out;
}

ResidualMap MapAlong(const Quantity& q, const std::vector<double>& dist2) {
  TWIN_REQUIRE(q.values.size() == dist2.size() && !dist2.empty(),
               "MapAlong: " + std::to_string(q.values.size()) + " values of " + q.name + ", " +
                   std::to_string(dist2.size()) + " residuals");
  ResidualMap m;
  m.quantity = q.name;
  m.unit = q.unit;
  const auto [lo_it, hi_it] = std::minmax_element(q.values.begin(), q.values.end());
  const double lo = *lo_it, hi = *hi_it;
  const int bins = hi > lo ? 8 : 1;
  std::vector<double> ss(bins, 0.0);
  m.count.assign(bins, 0);
  for (std::size_t i = 0; i < q.values.size(); ++i) {
    int b = hi > lo ? static_cast<int>((q.values[i] - lo) / (hi - lo) * bins) : 0;
    b = std::clamp(b, 0, bins - 1);
    ss[b] += dist2[i];
    ++m.count[b];
  }
  for (int b = 0; b < bins; ++b) {
    m.bin_centre.push_back(lo + (b + 0.5) * (hi - lo) / bins);
    m.rms_m.push_back(m.count[b] > 0 ? std::sqrt(ss[b] / m.count[b]) : 0.0);
  }
  return m;
}

void Evidence(const RobotModel& model, const Data& data, const CrossValidation& cv,
              DiscoveryResult* r) {
  const std::vector<Quantity> quantities = Quantities(model, data);
  r->evidence = StrongestCorrelations(quantities, data.ResidualComponents(cv), 8);
  for (const Quantity& q : quantities) r->maps.push_back(MapAlong(q, cv.dist2));
}

}  // namespace twin::discovery
