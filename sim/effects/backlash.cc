#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Dead band of width w [rad]: link - motor = -0.5 * w * sign(direction), the link lagging the
// motor against the last direction of motion (+1, -1); zero for a joint that never moved (0).
class Backlash : public Effect {
 public:
  Backlash(const EffectSpec& spec, double width) : spec_(spec), width_(width) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToTransmission(int robot, const JointVector&, const JointVector& direction,
                           JointVector* link_offset) const override {
    for (int j = 0; j < direction.size(); ++j) {
      if (!Applies(robot, j)) continue;
      const double sign = (direction(j) > 0.0) - (direction(j) < 0.0);
      (*link_offset)(j) += -0.5 * width_ * sign;
    }
  }

 private:
  EffectSpec spec_;
  double width_;  // [rad]
};

}  // namespace

std::unique_ptr<Effect> MakeBacklash(const EffectSpec& spec) {
  // At most 5 deg: worn gearboxes show a few tenths of a degree (plausibility limit).
  const Params params(spec, {Required("width_deg", kDegree, PositiveUpTo(5.0))});
  return std::make_unique<Backlash>(spec, params.Get("width_deg"));
}

}  // namespace twin::effects
