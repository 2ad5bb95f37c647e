#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// The base on springs (the joint-1 case of lateral elasticity: a pedestal, a floor plate, the
// anchors): the base body hangs on two passive hinges at the base origin about the base frame's
// x and y axes (horizontal on the floor and ceiling), each with a spring of stiffness k
// [N m/rad]. MuJoCo's gravity tilts the whole arm, base included, by the gravity moment about
// the base origin perpendicular to the base's z axis divided by k [rad].
class BaseCompliance : public Effect {
 public:
  BaseCompliance(const EffectSpec& spec, double stiffness) : spec_(spec), stiffness_(stiffness) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToStructure(int robot, StructureCompliance* structure) const override {
    if (Applies(robot)) structure->base_tilt_stiffness = stiffness_;
  }

 private:
  EffectSpec spec_;
  double stiffness_;  // [N m/rad]
};

}  // namespace

std::unique_ptr<Effect> MakeBaseCompliance(const EffectSpec& spec) {
  RequireAllJoints(spec, "base compliance tilts a robot's whole arm at its base");
  // Default 5e5 N m/rad: a pedestal bolted to a shop floor tilts by 1e-5 to 1e-4 rad under its
  // arm's own moment (industrial bases: 1e7-1e8 N m/rad under 1e3-1e4 N m); the twin's 23 kg
  // arm puts 20-70 N m on its base, which 5e5 N m/rad turns into 4e-5 to 1.4e-4 rad. Measured
  // at the flange of robot 2 over 48 poses (joint 1 at 80 deg, the others on a grid):
  // 0.003-0.10 mm, median 0.033 mm. Plausibility limits as for lateral_compliance: below 1e3
  // N m/rad the arm leans by degrees; above 1e10 N m/rad it is rigid.
  const Params params(spec,
                      {Optional("stiffness_Nm_per_rad", kUnitless, 5e5, Between(1e3, 1e10))});
  return std::make_unique<BaseCompliance>(spec, params.Get("stiffness_Nm_per_rad"));
}

}  // namespace twin::effects
