#include <cmath>

#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Periodic gear error: link - motor = amplitude [rad] * sin(harmonic * motor [rad] + phase
// [rad]), e.g. harmonic 1 for an eccentric output, 2 for an elliptic (harmonic-drive) one.
class TransmissionError : public Effect {
 public:
  TransmissionError(const EffectSpec& spec, double amplitude, double harmonic, double phase)
      : spec_(spec), amplitude_(amplitude), harmonic_(harmonic), phase_(phase) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToTransmission(int robot, const JointVector& motor, const JointVector&,
                           JointVector* link_offset) const override {
    for (int j = 0; j < motor.size(); ++j) {
      if (!Applies(robot, j)) continue;
      (*link_offset)(j) += amplitude_ * std::sin(harmonic_ * motor(j) + phase_);
    }
  }

 private:
  EffectSpec spec_;
  double amplitude_;  // [rad]
  double harmonic_;   // whole number >= 1 [-]
  double phase_;      // [rad]
};

}  // namespace

std::unique_ptr<Effect> MakeTransmissionError(const EffectSpec& spec) {
  // Plausibility limits: harmonic-drive transmission errors are arc minutes (5 deg is a
  // broken gear); harmonics above 1000 per turn are finer than the settling; a phase is
  // periodic.
  Range harmonic = IntegerAtLeast(1);
  harmonic.upper = 1000.0;
  const Params params(spec, {Required("amplitude_deg", kDegree, Between(-5.0, 5.0)),
                             Required("harmonic", kUnitless, harmonic),
                             Optional("phase_deg", kDegree, 0.0, Between(-360.0, 360.0))});
  return std::make_unique<TransmissionError>(spec, params.Get("amplitude_deg"),
                                             params.Get("harmonic"), params.Get("phase_deg"));
}

}  // namespace twin::effects
