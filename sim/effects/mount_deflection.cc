#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// A compliant bracket under the target (the chessboard) on a robot's flange: the target body
// hangs on three slide joints along the flange axes with springs, so MuJoCo's gravity deflects
// it by d_i [m] along flange axis i when gravity points along that axis (static deflection of
// the target's mass m under 1 g: spring stiffness k_i = m g / d_i). The deflection thus
// follows the flange's orientation to gravity, as a real bracket's does.
class MountDeflection : public Effect {
 public:
  MountDeflection(const EffectSpec& spec, const Vector3& deflection)
      : spec_(spec), deflection_(deflection) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToMount(int robot, MountCompliance* mount) const override {
    if (Applies(robot)) mount->deflection_F = deflection_;
  }

  bool NeedsCameraAndBoard() const override { return true; }

 private:
  EffectSpec spec_;
  Vector3 deflection_;  // [m]
};

}  // namespace

std::unique_ptr<Effect> MakeMountDeflection(const EffectSpec& spec) {
  RequireAllJoints(spec, "mount deflection acts on the target on a robot's flange");
  // Defaults: a light aluminium bracket under a 0.2 kg board sags a few hundredths of a
  // millimetre; 2 mm bounds typos (a bracket that soft would not hold a target).
  const Params params(spec, {Optional("deflection_x_mm", kMillimetre, 0.03, Between(0.0, 2.0)),
                             Optional("deflection_y_mm", kMillimetre, 0.03, Between(0.0, 2.0)),
                             Optional("deflection_z_mm", kMillimetre, 0.05, Between(0.0, 2.0))});
  return std::make_unique<MountDeflection>(
      spec, Vector3(params.Get("deflection_x_mm"), params.Get("deflection_y_mm"),
                    params.Get("deflection_z_mm")));
}

}  // namespace twin::effects
