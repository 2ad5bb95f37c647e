#include <cmath>

#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Finite encoder resolution: reading [rad] = round(reading / step) * step with
// step = 2 pi / counts_per_rev [rad].
class EncoderQuantization : public Effect {
 public:
  EncoderQuantization(const EffectSpec& spec, double counts_per_rev)
      : spec_(spec), step_(2.0 * kPi / counts_per_rev) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToEncoder(int robot, JointVector* reading, std::mt19937_64*) const override {
    for (int j = 0; j < reading->size(); ++j) {
      if (Applies(robot, j)) (*reading)(j) = std::round((*reading)(j) / step_) * step_;
    }
  }

 private:
  EffectSpec spec_;
  double step_;  // one count [rad]
};

}  // namespace

std::unique_ptr<Effect> MakeEncoderQuantization(const EffectSpec& spec) {
  // At least 2^10 counts: coarser encoders do not exist on industrial arms, and a smaller
  // number is most likely bits written as counts.
  // At most 2^32 counts per turn: finer than the servo's settling floor (plausibility limit).
  Range counts = IntegerAtLeast(1024);
  counts.upper = 4294967296.0;
  const Params params(spec, {Required("counts_per_rev", kUnitless, counts)});
  return std::make_unique<EncoderQuantization>(spec, params.Get("counts_per_rev"));
}

}  // namespace twin::effects
