#include "calib/model/parameters.h"

#include <array>

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
  FailPrecondition("kind is a DhParameter", "got " + std::to_string(kind), __FILE__, __LINE__);
}

}  // namespace

int ParameterIndex(int link, DhParameter which) {
  TWIN_REQUIRE(link >= 1 && link <= kMaxJoints + 1,
               "link " + std::to_string(link) + ", expected 1.." + std::to_string(kMaxJoints + 1));
  return kParamsPerLink * (link - 1) + static_cast<int>(which);
}

std::string ParameterName(const std::string& robot, int index) {
  TWIN_REQUIRE(index >= 0, "index " + std::to_string(index) + ", expected >= 0");
  return robot + ".link" + std::to_string(index / kParamsPerLink + 1) + "." +
         kKindNames[index % kParamsPerLink];
}

std::vector<std::string> ParameterNames(const KinematicModel& model) {
  std::vector<std::string> names;
  names.reserve(model.num_parameters());
  for (int i = 0; i < model.num_parameters(); ++i) names.push_back(ParameterName(model.name, i));
  return names;
}

int FindParameter(const KinematicModel& model, const std::string& name) {
  int found = -1;
  for (int i = 0; i < model.num_parameters() && found < 0; ++i) {
    if (ParameterName(model.name, i) == name) found = i;
  }
  TWIN_REQUIRE(found >= 0, "\"" + name + "\" is no kinematic parameter of " + model.name +
                               "; expected " + model.name + ".link<1.." +
                               std::to_string(model.num_links()) + ">.<theta|d|a|alpha|beta>");
  return found;
}

bool IsLengthParameter(int index) {
  const int kind = index % kParamsPerLink;
  return kind == static_cast<int>(DhParameter::kD) || kind == static_cast<int>(DhParameter::kA);
}

ParameterVector GetParameters(const KinematicModel& model) {
  ParameterVector p(model.num_parameters());
  for (int i = 0; i < model.num_parameters(); ++i) {
    DhParameters dh = model.links[i / kParamsPerLink].dh;
    p(i) = Field(dh, i % kParamsPerLink);
  }
  return p;
}

KinematicModel WithParameters(const KinematicModel& model, const ParameterVector& params) {
  TWIN_REQUIRE(params.size() == model.num_parameters(),
               std::to_string(params.size()) + " parameters for a model of " +
                   std::to_string(model.num_parameters()));
  KinematicModel out = model;
  for (int i = 0; i < model.num_parameters(); ++i) {
    Field(out.links[i / kParamsPerLink].dh, i % kParamsPerLink) = params(i);
  }
  return out;
}

}  // namespace twin
