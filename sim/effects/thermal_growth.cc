#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Uniform thermal expansion of the arm: d_i and a_i of all 7 links [m] are scaled by
// (1 + coefficient [1/K] * delta_T [K]); angles are unchanged.
class ThermalGrowth : public Effect {
 public:
  ThermalGrowth(const EffectSpec& spec, double delta_T, double scale)
      : spec_(spec), delta_T_(delta_T), scale_(scale) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToGeometry(int robot, KinematicModel* model, std::mt19937_64*) const override {
    if (!Applies(robot)) return;
    for (Link& link : model->links) {
      link.dh.d *= scale_;
      link.dh.a *= scale_;
    }
  }

  // The arm stands at its temperature change for the whole run.
  double TemperatureDeltaAt(int robot, double) const override {
    return Applies(robot) ? delta_T_ : 0.0;
  }

 private:
  EffectSpec spec_;
  double delta_T_;  // [K]
  double scale_;  // 1 + coefficient * delta_T [-]
};

}  // namespace

std::unique_ptr<Effect> MakeThermalGrowth(const EffectSpec& spec) {
  RequireAllJoints(spec, "thermal growth acts on every link of a robot");
  // Default: structural steel, 1.2e-5 /K (cast aluminium arms: about 2.3e-5 /K). The bounds
  // catch unit mistakes: no solid expands by 1e-3 /K, and a cell's temperature change is not
  // an absolute temperature.
  const Params params(
      spec, {Optional("coefficient_per_K", kUnitless, 1.2e-5, Between(0.0, 1e-3)),
             Required("delta_T_K", kUnitless, Between(-100.0, 100.0))});
  return std::make_unique<ThermalGrowth>(
      spec, params.Get("delta_T_K"), 1.0 + params.Get("coefficient_per_K") * params.Get("delta_T_K"));
}

}  // namespace twin::effects
