#include <cmath>

#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// The arm warming up while it works (a cold start): its temperature rises towards
// delta_T_K above the start with a first-order lag of time constant tau, and d_i and a_i of
// every link (the tool link too) grow with it:
//   scale(t) = 1 + coefficient * delta_T * (1 - exp(-t / tau)),  t = the twin's clock [s].
// Angles are unchanged. The scale is 1 at t = 0, so the static geometry (TwinTruth::models)
// is the arm at the start of the session.
class ThermalDrift : public Effect {
 public:
  ThermalDrift(const EffectSpec& spec, double delta_T, double growth, double tau)
      : spec_(spec), delta_T_(delta_T), growth_(growth), tau_(tau) {}

  const EffectSpec& spec() const override { return spec_; }

  bool DriftsLengths(int robot) const override { return Applies(robot) && growth_ != 0.0; }

  double LengthScaleAt(int robot, double time_s) const override {
    if (!Applies(robot)) return 1.0;
    return 1.0 - growth_ * std::expm1(-std::max(0.0, time_s) / tau_);
  }

  // The growth follows the temperature: both are delta_T (1 - exp(-t / tau)) shaped.
  double TemperatureDeltaAt(int robot, double time_s) const override {
    if (!Applies(robot)) return 0.0;
    return -delta_T_ * std::expm1(-std::max(0.0, time_s) / tau_);
  }

 private:
  EffectSpec spec_;
  double delta_T_;  // the warming towards equilibrium [K]
  double growth_;  // coefficient * delta_T: the final relative growth [-]
  double tau_;     // [s]
};

}  // namespace

std::unique_ptr<Effect> MakeThermalDrift(const EffectSpec& spec) {
  RequireAllJoints(spec, "thermal drift acts on every link of a robot");
  // Defaults: a steel arm (1.2e-5 /K; cast aluminium about 2.3e-5 /K) warming 5 K over its
  // first hours of work, time constant 30 min (industrial arms reach thermal equilibrium in
  // one to a few hours). Bounds: no solid expands by 1e-3 /K; an arm does not warm by 50 K
  // while it works; a time constant below a minute or above a day is a unit mistake.
  const Params params(
      spec, {Optional("coefficient_per_K", kUnitless, 1.2e-5, Between(0.0, 1e-3)),
             Optional("delta_T_K", kUnitless, 5.0, Between(-50.0, 50.0)),
             Optional("time_constant_s", kUnitless, 1800.0, Between(60.0, 86400.0))});
  return std::make_unique<ThermalDrift>(
      spec, params.Get("delta_T_K"), params.Get("coefficient_per_K") * params.Get("delta_T_K"),
      params.Get("time_constant_s"));
}

}  // namespace twin::effects
