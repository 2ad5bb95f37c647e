// What a measurement carries besides its reading (DESIGN.md, estimator model): the joint
// readings of the robot when it was taken, each joint's approach direction, the time stamp and
// the temperature change, as far as they are known. Error terms read what they need from it.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "calib/kinematics/kinematic_model.h"

namespace twin {

/// The context of one measurement of one robot.
struct MeasurementContext {
  JointVector q;  ///< joint encoder readings (motor side) [rad], one per joint
  /// Sign of each joint's last motion before the reading (+1, -1; 0 when it did not move or is
  /// unknown). Empty: unknown for every joint.
  JointVector approach;
  double time_s = std::numeric_limits<double>::quiet_NaN();  ///< time stamp [s]; NaN unknown
  /// Temperature change from the reference state of the nominal model [K]; NaN unknown.
  double temperature_delta_K = std::numeric_limits<double>::quiet_NaN();

  bool has_time() const { return std::isfinite(time_s); }
  bool has_temperature() const { return std::isfinite(temperature_delta_K); }
  /// Approach direction of joint i (0 when unknown).
  double approach_of(int i) const { return i < approach.size() ? approach(i) : 0.0; }
};

/// Each joint's approach direction for a move from readings `before` to target `q`: the sign
/// of the commanded motion (+1, -1; 0 for a joint that did not move).
inline JointVector ApproachDirections(const JointVector& before, const JointVector& q) {
  JointVector a(q.size());
  for (int i = 0; i < q.size(); ++i) a(i) = q(i) > before(i) ? 1.0 : (q(i) < before(i) ? -1.0 : 0.0);
  return a;
}

/// A context with readings q and nothing else known.
inline MeasurementContext ContextOf(const JointVector& q) {
  MeasurementContext c;
  c.q = q;
  return c;
}

}  // namespace twin
