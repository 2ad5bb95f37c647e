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
  const Params params(spec, {Required("stiffness_Nm_per_rad", kUnitless, Positive())});
  return std::make_unique<JointCompliance>(spec, params.Get("stiffness_Nm_per_rad"));
}

}  // namespace twin::effects
