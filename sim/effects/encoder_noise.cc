#include <random>

#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Encoder noise: reading [rad] += N(0, sigma [rad]), independently per joint and reading.
class EncoderNoise : public Effect {
 public:
  EncoderNoise(const EffectSpec& spec, double sigma) : spec_(spec), sigma_(sigma) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToEncoder(int robot, JointVector* reading, std::mt19937_64* rng) const override {
    std::normal_distribution<double> noise(0.0, sigma_);
    for (int j = 0; j < reading->size(); ++j) {
      if (Applies(robot, j)) (*reading)(j) += noise(*rng);
    }
  }

 private:
  EffectSpec spec_;
  double sigma_;  // [rad]
};

}  // namespace

std::unique_ptr<Effect> MakeEncoderNoise(const EffectSpec& spec) {
  // At most 1 deg per reading: industrial encoders jitter by 1e-4 deg; beyond a degree no
  // calibration result means anything (plausibility limit).
  const Params params(spec, {Required("sigma_deg", kDegree, PositiveUpTo(1.0))});
  return std::make_unique<EncoderNoise>(spec, params.Get("sigma_deg"));
}

}  // namespace twin::effects
