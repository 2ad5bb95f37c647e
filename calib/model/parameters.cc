#include "calib/model/parameters.h"

#include <array>
#include <cassert>

#include "calib/common/errors.h"

namespace twin {
namespace {

constexpr std::array<const char*, kParamsPerLink> kKindNames = {"theta", "d", "a", "alpha",
                                                                "beta"};

double& Field(DhParameters& dh, int kind) {
  switch (static_cast<DhParameter>(kind)) {
    case DhParameter::kTheta: return dh.theta_offset;
    case DhParameter::kD: return dh.d;
    case DhParameter::kA: return dh.a;
    case DhParameter::kAlpha: return dh.alpha;
    case DhParameter::kBeta: return dh.beta;
  }
  assert(false && "bad DhParameter");
  return dh.theta_offset;
}

}  // namespace

int ParameterIndex(int link, DhParameter which) {
  assert(link >= 1 && link <= kNumLinks);
  return kParamsPerLink * (link - 1) + static_cast<int>(which);
}

std::string ParameterName(const std::string& robot, int index) {
  assert(index >= 0 && index < kNumParams);
  return robot + ".link" + std::to_string(index / kParamsPerLink + 1) + "." +
         kKindNames[index % kParamsPerLink];
}

std::vector<std::string> ParameterNames(const std::string& robot) {
  std::vector<std::string> names;
  names.reserve(kNumParams);
  for (int i = 0; i < kNumParams; ++i) names.push_back(ParameterName(robot, i));
  return names;
}

int FindParameter(const std::string& robot, const std::string& name) {
  for (int i = 0; i < kNumParams; ++i) {
    if (ParameterName(robot, i) == name) return i;
  }
  throw InputError(name, "unknown kinematic parameter; expected " + robot +
                             ".link<1..7>.<theta|d|a|alpha|beta>");
}

bool IsLengthParameter(int index) {
  const int kind = index % kParamsPerLink;
  return kind == static_cast<int>(DhParameter::kD) || kind == static_cast<int>(DhParameter::kA);
}

ParameterVector GetParameters(const KinematicModel& model) {
  ParameterVector p;
  for (int i = 0; i < kNumParams; ++i) {
    DhParameters dh = model.links[i / kParamsPerLink].dh;
    p(i) = Field(dh, i % kParamsPerLink);
  }
  return p;
}

KinematicModel WithParameters(const KinematicModel& model, const ParameterVector& params) {
  KinematicModel out = model;
  for (int i = 0; i < kNumParams; ++i) {
    Field(out.links[i / kParamsPerLink].dh, i % kParamsPerLink) = params(i);
  }
  return out;
}

}  // namespace twin
