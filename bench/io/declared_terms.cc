#include "bench/io/declared_terms.h"

#include <cmath>

#include "calib/model/error_term.h"

namespace twin {

RobotModel DeclaredModel(const Scenario& sc, int robot, const KinematicModel& nominal,
                         std::vector<std::string>* notes) {
  RobotModel m = MakeRobotModel(nominal);
  const std::string where = sc.path + " scenario.effects";
  for (const EffectSpec& e : sc.twin.effects) {
    if (!e.declared || (e.robot != -1 && e.robot != robot)) continue;
    std::vector<TermSpec> specs;
    const auto per_joint = [&](const std::string& type, std::vector<int> orders) {
      for (int j = 0; j < nominal.num_joints(); ++j) {
        if (e.joint == -1 || e.joint == j) specs.push_back({type, j, orders});
      }
    };
    if (e.type == "joint_compliance" || e.type == "backlash") {
      per_joint(e.type, {});
    } else if (e.type == "transmission_error") {
      const auto h = e.params.find("harmonic");
      per_joint(e.type, {h != e.params.end() ? static_cast<int>(std::lround(h->second)) : 1});
    } else if (e.type == "lateral_compliance") {
      per_joint(e.type, {});
    } else if (e.type == "base_compliance") {
      // The whole arm tilting at its base under the gravity moment there: the estimator's
      // lateral compliance of joint 1, whose tilt includes the base's (terms/lateral_compliance).
      specs.push_back({"lateral_compliance", 0, {}});
    } else if (e.type == "axis_wobble") {
      const auto h = e.params.find("order");
      per_joint(e.type, {h != e.params.end() ? static_cast<int>(std::lround(h->second)) : 2});
    } else if (e.type == "mount_deflection") {
      specs.push_back({e.type, -1, {}});
    } else if (e.type == "thermal_drift") {
      // The twin's thermal_drift is a warm-up from a cold start (a first-order lag): the
      // estimator's thermal_warmup, its time constant estimated from a start of
      // kDeclaredWarmupStartMin (not the twin's: declared is the type, never a value).
      specs.push_back({"thermal_warmup", -1, {kDeclaredWarmupStartMin}});
    } else if (e.type == "thermal_growth") {
      notes->push_back("declared thermal_growth is not modelled: the procedure records no "
                       "temperature");
    }
    for (const TermSpec& spec : specs) {
      bool present = false;
      for (const auto& t : m.terms) {
        const TermSpec& have = t->spec();
        present = present || (have.type == spec.type && have.joint == spec.joint &&
                              have.orders == spec.orders);
      }
      if (!present) m = WithTerm(m, MakeErrorTerm(spec, nominal, nominal.name, where));
    }
  }
  return m;
}

}  // namespace twin
