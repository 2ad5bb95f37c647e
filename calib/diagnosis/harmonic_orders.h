// Which harmonic orders model discovery tries for the periodic terms (transmission error, axis
// wobble) of each joint (model_discovery.h, step 3): the orders the residual's spectrum over that
// joint's reading shows most of, up to the highest its sampled range resolves, rather than a
// fixed list. Internal to calib/diagnosis.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "calib/model/measurement_context.h"

namespace twin::discovery {

/// The highest order the readings `q` of one joint resolve: their spacing over the range they
/// cover, R / (m - 1) with m distinct readings, samples a sinusoid of order h at least twice a
/// period (h <= pi (m - 1) / R), at most `max_order`; 0 for a joint that does not move.
int ResolvedOrder(const std::vector<double>& q, int max_order);

/// Per order h = 1..ResolvedOrder, the residual's power at that order over the joint's reading:
/// the sum over the residual's components of what a least-squares fit of a + b sin(h q) +
/// c cos(h q) explains beyond the mean [m^2]. `residuals[i]` is unit i's residual (any length,
/// the same for every unit), `q[i]` its reading.
std::vector<double> HarmonicPower(const std::vector<Eigen::VectorXd>& residuals,
                                  const std::vector<double>& q, int max_order);

/// The orders to try for each joint: the `per_joint` orders of largest HarmonicPower (the lower
/// order on a tie), ascending; none for a joint that does not move. `contexts[i]` holds unit i's
/// readings.
std::vector<std::vector<int>> SpectrumOrders(const std::vector<Eigen::VectorXd>& residuals,
                                             const std::vector<const MeasurementContext*>& contexts,
                                             int joints, int max_order, int per_joint);

/// The same with each joint's own residuals: `residuals[j][i]` unit i's residual as joint j's
/// spectrum reads it (in the frame of link j, which turns with the joint: an error of joint j
/// at order h, seen through a lever arm that turns with the joint, is then at order h, not at
/// h - 1 and h + 1 as in a fixed frame).
std::vector<std::vector<int>> SpectrumOrdersPerJoint(
    const std::vector<std::vector<Eigen::VectorXd>>& residuals,
    const std::vector<const MeasurementContext*>& contexts, int max_order, int per_joint);

/// `orders` with order 1 added to every joint that has any (ascending). The fundamental is tried
/// whatever the spectrum shows: the geometric fit the residual comes from absorbs much of a
/// joint's order-1 error (an axis tilt or an offset looks like it over part of a turn), so it can
/// rank below the leftovers of other orders although the term explains it whole.
std::vector<std::vector<int>> WithFundamental(std::vector<std::vector<int>> orders);

}  // namespace twin::discovery
