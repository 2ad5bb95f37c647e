#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Compliant joints: the drive's stiffness is k [N m/rad] with no gravity feed-forward, so a
// link sags by gravity torque / k [rad] in steady state.
class JointCompliance : public Effect {
 public:
  JointCompliance(const EffectSpec& spec, double stiffness)
      : spec_(spec), stiffness_(stiffness) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToDrive(int robot, std::vector<JointDrive>* drives) const override {
    for (int j = 0; j < static_cast<int>(drives->size()); ++j) {
      if (!Applies(robot, j)) continue;
      (*drives)[j].stiffness = stiffness_;
      (*drives)[j].gravity_feedforward = false;
    }
  }

 private:
  EffectSpec spec_;
  double stiffness_;  // [N m/rad]
};

}  // namespace

std::unique_ptr<Effect> MakeJointCompliance(const EffectSpec& spec) {
  // Plausibility limits: below 100 N m/rad an arm of this size sags by tens of degrees; above
  // 1e9 N m/rad the joint is rigid for any purpose.
  const Params params(spec, {Required("stiffness_Nm_per_rad", kUnitless, Between(100.0, 1e9))});
  return std::make_unique<JointCompliance>(spec, params.Get("stiffness_Nm_per_rad"));
}

}  // namespace twin::effects
