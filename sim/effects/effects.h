// Factories of the registered effects, one per file in sim/effects/, listed in the registry
// table (sim/effects/registry.cc). Each checks its spec.params and throws InputError naming
// spec.where; spec.robot and spec.joint ranges are checked by MakeEffect before the call.
// Adding an effect: one file defining its class and factory, one declaration here, one line
// in the registry table.
#pragma once

#include <memory>

#include "sim/effects/effect.h"

namespace twin::effects {

/// "geometry_errors": kinematic errors of the true geometry (random and/or explicit).
std::unique_ptr<Effect> MakeGeometryErrors(const EffectSpec& spec);
/// "thermal_growth": d and a of every link scaled by 1 + coefficient * delta_T.
std::unique_ptr<Effect> MakeThermalGrowth(const EffectSpec& spec);
/// "thermal_drift": d and a of every link grow over the twin's clock (the arm warming up).
std::unique_ptr<Effect> MakeThermalDrift(const EffectSpec& spec);
/// "joint_compliance": finite drive stiffness without gravity feed-forward.
std::unique_ptr<Effect> MakeJointCompliance(const EffectSpec& spec);
/// "transmission_error": periodic link-minus-motor error.
std::unique_ptr<Effect> MakeTransmissionError(const EffectSpec& spec);
/// "backlash": dead band, link lags the motor by half its width.
std::unique_ptr<Effect> MakeBacklash(const EffectSpec& spec);
/// "encoder_quantization": readings rounded to whole encoder counts.
std::unique_ptr<Effect> MakeEncoderQuantization(const EffectSpec& spec);
/// "encoder_noise": Gaussian noise on joint readings.
std::unique_ptr<Effect> MakeEncoderNoise(const EffectSpec& spec);
/// "mount_deflection": the target's bracket deflects under gravity (spring-mounted target).
std::unique_ptr<Effect> MakeMountDeflection(const EffectSpec& spec);
/// "lateral_compliance": a joint's axis tilts under the bending moment it carries (springs).
std::unique_ptr<Effect> MakeLateralCompliance(const EffectSpec& spec);
/// "base_compliance": the whole arm tilts on its base under the gravity moment (springs).
std::unique_ptr<Effect> MakeBaseCompliance(const EffectSpec& spec);
/// "axis_wobble": a joint's axis tilts periodically with its own angle (bearing runout).
std::unique_ptr<Effect> MakeAxisWobble(const EffectSpec& spec);
/// "image_noise": Gaussian grey-level noise on camera images.
std::unique_ptr<Effect> MakeImageNoise(const EffectSpec& spec);

}  // namespace twin::effects
