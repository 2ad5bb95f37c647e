#include <cmath>

#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Bearing runout: joint i's axis tilts, about the origin of the parent's DH frame L(i-1) (a
// point of the axis), as a periodic function of its own link-side angle q [rad]:
//   rotation about x of L(i-1) = A sin(h q + phase),  about y of L(i-1) = A cos(h q + phase)
// [rad], applied before the joint's rotation. The tilt has magnitude A and a direction, in the
// parent, that turns by -h times the joint's rotation (it counter-rotates). A tilt whose
// direction is fixed in the parent (order 0), or turns with the joint (+1: fixed in the
// link), would be a constant geometric error; a counter-rotating one of any order h >= 1 is
// not. Kinematic (no spring): the twin turns the joint's body as its angle changes; the drive
// and the encoder do not see it.
class AxisWobble : public Effect {
 public:
  AxisWobble(const EffectSpec& spec, double amplitude, double order, double phase)
      : spec_(spec), amplitude_(amplitude), order_(order), phase_(phase) {}

  const EffectSpec& spec() const override { return spec_; }

  bool TiltsAxes(int robot) const override { return Applies(robot); }

  void AddAxisTilt(int robot, const JointVector& q_link,
                   std::vector<Eigen::Vector2d>* tilt) const override {
    for (int j = 0; j < q_link.size(); ++j) {
      if (!Applies(robot, j)) continue;
      const double angle = order_ * q_link(j) + phase_;
      (*tilt)[j] += amplitude_ * Eigen::Vector2d(std::sin(angle), std::cos(angle));
    }
  }

 private:
  EffectSpec spec_;
  double amplitude_;  // A [rad]
  double order_;      // h, whole number >= 1 [-]
  double phase_;      // [rad]
};

}  // namespace

std::unique_ptr<Effect> MakeAxisWobble(const EffectSpec& spec) {
  // Default amplitude 5e-5 rad: the tilting runout of the precision cross-roller bearings of
  // industrial joints is 5-20 um over a 100-300 mm race, 2e-5 to 1e-4 rad. Default order 2:
  // ovality of a race, the commonest form error of a thin bearing ring. Measured at the flange
  // of robot 2 over 48 poses: joint 1 0.005-0.041 mm (median 0.028), joint 2 up to 0.031 mm,
  // joint 4 0.019-0.022 mm. Plausibility limits: a
  // wobble of 0.01 rad (0.6 deg) is a broken bearing; orders above 200 are finer than the
  // rolling elements of any joint bearing; a phase is periodic.
  Range order = IntegerAtLeast(1);
  order.upper = 200.0;
  const Params params(spec, {Optional("amplitude_rad", kUnitless, 5e-5, PositiveUpTo(0.01)),
                             Optional("order", kUnitless, 2.0, order),
                             Optional("phase_rad", kUnitless, 0.0, Between(-2 * kPi, 2 * kPi))});
  return std::make_unique<AxisWobble>(spec, params.Get("amplitude_rad"), params.Get("order"),
                                      params.Get("phase_rad"));
}

}  // namespace twin::effects
