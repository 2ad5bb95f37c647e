// The error-term registry: the one table from type names to factories (DESIGN.md: no string
// dispatch chains). Adding a term adds one line here.
#include <algorithm>
#include <cmath>
#include <set>

#include "calib/common/errors.h"
#include "calib/model/error_term.h"
#include "calib/model/terms/terms.h"

namespace twin {
namespace {

/// What a term acts on, for checking specs and enumerating discovery candidates.
enum class Scope {
  kJoint,          ///< one joint (spec.joint required)
  kJointPeriodic,  ///< one joint and harmonic orders
  kRobot,          ///< the whole robot (spec.joint must be -1)
  kRobotTimeConstant,  ///< the whole robot, one order: a time constant in minutes
};

struct Registration {
  const char* type;  ///< TermSpec::type
  Scope scope;
  std::shared_ptr<const ErrorTerm> (*make)(const terms::TermInput& in);
};

// Time constants of the warm-up candidates [min]: doubling from 10 min (a light arm, a short
// duty cycle) to 80 min (a heavy one); industrial arms settle thermally in one to a few hours.
constexpr int kWarmupCandidateMinutes[] = {10, 20, 40, 80};
constexpr int kMaxTimeConstantMinutes = 24 * 60;
constexpr int kMaxHarmonicOrder = 8;  // a gear error above 8 cycles per turn is not a geometric
                                      // model's business (and aliases with sparse poses)

constexpr Registration kRegistry[] = {
    {"joint_compliance", Scope::kJoint, terms::MakeJointCompliance},
    {"transmission_error", Scope::kJointPeriodic, terms::MakeTransmissionError},
    {"backlash", Scope::kJoint, terms::MakeBacklash},
    {"thermal_growth", Scope::kRobot, terms::MakeThermalGrowth},
    {"thermal_drift", Scope::kRobot, terms::MakeThermalDrift},
    {"thermal_warmup", Scope::kRobotTimeConstant, terms::MakeThermalWarmup},
    {"mount_deflection", Scope::kRobot, terms::MakeMountDeflection},
    {"lateral_compliance", Scope::kJoint, terms::MakeLateralCompliance},
    {"axis_wobble", Scope::kJointPeriodic, terms::MakeAxisWobble},
};

std::string KnownTypes() {
  std::string text;
  for (const Registration& r : kRegistry) text += (text.empty() ? "" : ", ") + std::string(r.type);
  return text;
}

const Registration& Find(const std::string& type, const std::string& where) {
  for (const Registration& r : kRegistry) {
    if (type == r.type) return r;
  }
  throw InputError(where, "unknown error term \"" + type + "\"; known terms: " + KnownTypes());
}

}  // namespace

namespace terms {

std::string JointPrefix(const std::string& robot, int joint) {
  return robot + ".joint" + std::to_string(joint + 1);
}

double NominalReach(const KinematicModel& nominal) {
  double reach = 0.0;
  for (const Link& l : nominal.links) reach += std::abs(l.dh.d) + std::abs(l.dh.a);
  return std::max(reach, 0.1);
}

}  // namespace terms

std::shared_ptr<const ErrorTerm> MakeErrorTerm(const TermSpec& spec, const KinematicModel& nominal,
                                               const std::string& robot_name,
                                               const std::string& where) {
  const Registration& r = Find(spec.type, where);
  const int n = nominal.num_joints();
  if (r.scope == Scope::kRobot || r.scope == Scope::kRobotTimeConstant) {
    if (spec.joint != -1) {
      throw InputError(where, spec.type + " acts on the whole robot; it takes no joint");
    }
  } else if (spec.joint < 0 || spec.joint >= n) {
    throw InputError(where, spec.type + " needs a joint from 1 to " + std::to_string(n) +
                                ", got " + std::to_string(spec.joint + 1));
  }
  if (r.scope == Scope::kJointPeriodic) {
    if (spec.orders.empty()) throw InputError(where, spec.type + " needs harmonic orders");
    std::set<int> seen;
    for (int h : spec.orders) {
      if (h < 1 || h > kMaxHarmonicOrder || !seen.insert(h).second) {
        throw InputError(where, spec.type + ": harmonic orders must be distinct whole numbers "
                                            "from 1 to " + std::to_string(kMaxHarmonicOrder) +
                                    ", got " + std::to_string(h));
      }
    }
  } else if (r.scope == Scope::kRobotTimeConstant) {
    if (spec.orders.size() != 1 || spec.orders[0] < 1 ||
        spec.orders[0] > kMaxTimeConstantMinutes) {
      throw InputError(where, spec.type + " needs one order, its time constant in whole minutes "
                                          "from 1 to " +
                                  std::to_string(kMaxTimeConstantMinutes) +
                                  " (e.g. thermal_warmup::30)");
    }
  } else if (!spec.orders.empty()) {
    throw InputError(where, spec.type + " takes no harmonic orders");
  }
  return r.make({spec, nominal, robot_name, where});
}

std::vector<std::string> ErrorTermTypes() {
  std::vector<std::string> types;
  for (const Registration& r : kRegistry) types.emplace_back(r.type);
  return types;
}

int MaxHarmonicOrder() { return kMaxHarmonicOrder; }

std::vector<TermSpec> CandidateTermSpecs(const KinematicModel& nominal,
                                         const std::vector<std::vector<int>>& orders) {
  TWIN_REQUIRE(orders.empty() || static_cast<int>(orders.size()) == nominal.num_joints(),
               "harmonic orders for " + std::to_string(orders.size()) + " joints of " +
                   std::to_string(nominal.num_joints()));
  std::vector<TermSpec> out;
  for (const Registration& r : kRegistry) {
    switch (r.scope) {
      case Scope::kRobot:
        out.push_back({r.type, -1, {}});
        break;
      case Scope::kRobotTimeConstant:
        for (int minutes : kWarmupCandidateMinutes) out.push_back({r.type, -1, {minutes}});
        break;
      case Scope::kJoint:
        for (int j = 0; j < nominal.num_joints(); ++j) out.push_back({r.type, j, {}});
        break;
      case Scope::kJointPeriodic:
        for (int j = 0; j < nominal.num_joints(); ++j) {
          for (int h : orders.empty() ? std::vector<int>{1, 2} : orders[j]) {
            out.push_back({r.type, j, {h}});
          }
        }
        break;
    }
  }
  return out;
}

std::string TermLabel(const TermSpec& spec) {
  std::string label = spec.type;
  if (spec.type == "thermal_warmup" && spec.orders.size() == 1 && spec.joint < 0) {
    return label + " (time constant " + std::to_string(spec.orders[0]) + " min)";
  }
  if (spec.joint >= 0 || !spec.orders.empty()) {
    label += " (";
    if (spec.joint >= 0) label += "joint " + std::to_string(spec.joint + 1);
    for (size_t k = 0; k < spec.orders.size(); ++k) {
      label += (k == 0 ? (spec.joint >= 0 ? ", order " : "order ") : ", ") +
               std::to_string(spec.orders[k]);
    }
    label += ")";
  }
  return label;
}

}  // namespace twin
