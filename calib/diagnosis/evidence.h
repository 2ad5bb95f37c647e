// The residual's evidence (internal to calib/diagnosis; model_discovery.h, step 4): its
// correlations with the quantities an effect could follow (joint angles, gravity torques,
// acquisition order, time, temperature) and its RMS binned along each.
#pragma once

#include <string>
#include <vector>

#include "calib/diagnosis/discovery_data.h"

namespace twin::discovery {

/// A quantity the residual is correlated with and mapped against, per unit of data.
struct Quantity {
  std::string name, unit;
  std::vector<double> values;
};

/// Per unit: q1..qn, tau1..taun (gravity torques of `model`), order, and time and temperature
/// where every unit has them.
std::vector<Quantity> Quantities(const RobotModel& model, const Data& data);

/// Pearson's r of every quantity with every residual component (quantity-major order), the
/// strongest |r| first (stable), at most `keep`.
std::vector<ResidualCorrelation> StrongestCorrelations(const std::vector<Quantity>& quantities,
                                                       const Components& components,
                                                       int keep);

/// The residual RMS (from the squared distances `dist2`, per unit) in 8 equal bins of the
/// quantity's range (one bin where it is constant). Requires one value per unit.
ResidualMap MapAlong(const Quantity& q, const std::vector<double>& dist2);

/// r->evidence (the 8 strongest correlations) and r->maps (one per quantity) of the held-out
/// residuals `cv` of `data`.
void Evidence(const RobotModel& model, const Data& data, const CrossValidation& cv,
              DiscoveryResult* r);

}  // namespace twin::discovery
