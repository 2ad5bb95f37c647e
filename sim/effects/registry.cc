// The effect registry: the one table from type names to factories (DESIGN.md: no string
// dispatch chains). Adding an effect adds one line here.
#include <string>

#include "calib/common/errors.h"
#include "sim/effects/effect.h"
#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin {
namespace {

struct Registration {
  const char* type;                                        ///< EffectSpec::type
  std::unique_ptr<Effect> (*make)(const EffectSpec& spec);  ///< checks params, builds
};

constexpr Registration kRegistry[] = {
    {"geometry_errors", effects::MakeGeometryErrors},
    {"thermal_growth", effects::MakeThermalGrowth},
    {"thermal_drift", effects::MakeThermalDrift},
    {"joint_compliance", effects::MakeJointCompliance},
    {"transmission_error", effects::MakeTransmissionError},
    {"backlash", effects::MakeBacklash},
    {"encoder_quantization", effects::MakeEncoderQuantization},
    {"encoder_noise", effects::MakeEncoderNoise},
    {"image_noise", effects::MakeImageNoise},
    {"mount_deflection", effects::MakeMountDeflection},
    {"lateral_compliance", effects::MakeLateralCompliance},
    {"base_compliance", effects::MakeBaseCompliance},
    {"axis_wobble", effects::MakeAxisWobble},
};

// Checks the fields every effect shares: robot -1, 0..kMaxRobots-1; joint -1, 0..kMaxJoints-1
// (ValidateTwinSpec checks both against the cell's robots and their own joint counts).
void ValidateTargets(const EffectSpec& spec) {
  if (spec.robot < -1 || spec.robot >= kMaxRobots) {
    throw InputError(spec.where, effects::EffectLabel(spec) + "robot = " +
                                     std::to_string(spec.robot) + ", expected -1 (every robot) "
                                     "or 0.." + std::to_string(kMaxRobots - 1));
  }
  if (spec.joint < -1 || spec.joint >= kMaxJoints) {
    throw InputError(spec.where, effects::EffectLabel(spec) + "joint = " +
                                     std::to_string(spec.joint) +
                                     ", expected -1 (every joint) or 0.." +
                                     std::to_string(kMaxJoints - 1));
  }
}

std::string KnownTypes() {
  std::string text;
  for (const Registration& r : kRegistry) {
    text += (text.empty() ? "" : ", ") + std::string(r.type);
  }
  return text;
}

}  // namespace

std::unique_ptr<Effect> MakeEffect(const EffectSpec& spec) {
  for (const Registration& r : kRegistry) {
    if (spec.type == r.type) {
      ValidateTargets(spec);
      return r.make(spec);
    }
  }
  throw InputError(spec.where,
                   "unknown effect type \"" + spec.type + "\"; known types: " + KnownTypes());
}

std::vector<std::unique_ptr<Effect>> MakeEffects(const TwinSpec& spec) {
  std::vector<std::unique_ptr<Effect>> made;
  for (const EffectSpec& e : spec.effects) {
    made.push_back(MakeEffect(e));
    if (made.back()->NeedsCameraAndBoard() && !spec.HasCameraAndBoard()) {
      throw InputError(e.where, effects::EffectLabel(e) + "acts through the hand camera or the "
                                "board, which a one-robot cell does not have");
    }
  }
  return made;
}

std::vector<std::string> EffectTypes() {
  std::vector<std::string> types;
  for (const Registration& r : kRegistry) types.emplace_back(r.type);
  return types;
}

}  // namespace twin
