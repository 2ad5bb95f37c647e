#include <random>

#include "calib/common/errors.h"
#include "calib/model/parameters.h"
#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Key of the explicit delta of flat parameter `index`: its name without the robot prefix plus
// the unit, e.g. "link3.alpha_deg", "link2.d_mm" (names come from calib/model/parameters.h).
std::string DeltaKey(int index) {
  const std::string name = ParameterName("r", index);  // "r.link3.alpha"
  return name.substr(2) + (IsLengthParameter(index) ? "_mm" : "_deg");
}

// Kinematic errors of the true geometry: p_i += N(0, sigma_length [m] or sigma_angle [rad])
// for each of the 5 (N + 1) parameters, then p_i += delta_i [m or rad] for the explicit deltas
// (keys exist for chains up to kMaxJoints; a delta beyond the robot's last link is refused).
constexpr int kMaxDeltas = kParamsPerLink * (kMaxJoints + 1);
class GeometryErrors : public Effect {
 public:
  GeometryErrors(const EffectSpec& spec, double sigma_length, double sigma_angle,
                 const ParameterVector& delta)
      : spec_(spec), sigma_length_(sigma_length), sigma_angle_(sigma_angle), delta_(delta) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToGeometry(int robot, KinematicModel* model, std::mt19937_64* rng) const override {
    if (!Applies(robot)) return;
    ParameterVector p = GetParameters(*model);
    const int n = static_cast<int>(p.size());
    for (int i = n; i < kMaxDeltas; ++i) {
      if (delta_(i) != 0.0) {
        throw InputError(spec_.where, EffectLabel(spec_) + DeltaKey(i) + ": robot " +
                                          model->name + " has only " +
                                          std::to_string(model->num_links()) + " links");
      }
    }
    std::normal_distribution<double> unit_normal(0.0, 1.0);
    for (int i = 0; i < n; ++i) {
      const double sigma = IsLengthParameter(i) ? sigma_length_ : sigma_angle_;
      if (sigma > 0.0) p(i) += sigma * unit_normal(*rng);
    }
    *model = WithParameters(*model, p + delta_.head(n));
  }

 private:
  EffectSpec spec_;
  double sigma_length_;     // [m]
  double sigma_angle_;      // [rad]
  ParameterVector delta_;   // explicit deltas, flat order [m, rad]
};

}  // namespace

std::unique_ptr<Effect> MakeGeometryErrors(const EffectSpec& spec) {
  RequireAllJoints(spec, "geometry errors act on every link of a robot");
  // Plausibility limits: uncalibrated arms are off by a few millimetres and tenths of a degree
  // (Zhu et al. 2019, Table 3: up to ~6 mm, ~0.6 deg); beyond 50 mm / 5 deg per parameter (or
  // 100 mm / 10 deg for one explicit error) the nominal model does not describe the arm.
  std::vector<ParamDef> defs = {Optional("sigma_length_mm", kMillimetre, 0.0, Between(0.0, 50.0)),
                                Optional("sigma_angle_deg", kDegree, 0.0, Between(0.0, 5.0))};
  for (int i = 0; i < kMaxDeltas; ++i) {
    defs.push_back(Optional(DeltaKey(i), IsLengthParameter(i) ? kMillimetre : kDegree, 0.0,
                            IsLengthParameter(i) ? Between(-100.0, 100.0) : Between(-10.0, 10.0)));
  }
  const Params params(spec, defs,
                      "sigma_length_mm, sigma_angle_deg, link<i>.<theta|alpha|beta>_deg, "
                      "link<i>.<d|a>_mm (i = 1..N+1, N+1 the tool link)");
  if (spec.params.empty()) {
    throw InputError(spec.where, EffectLabel(spec) +
                                     "no parameters; expected sigma_length_mm, sigma_angle_deg "
                                     "and/or deltas such as link3.alpha_deg");
  }
  ParameterVector delta(kMaxDeltas);
  for (int i = 0; i < kMaxDeltas; ++i) delta(i) = params.Get(DeltaKey(i));
  return std::make_unique<GeometryErrors>(spec, params.Get("sigma_length_mm"),
                                          params.Get("sigma_angle_deg"), delta);
}

}  // namespace twin::effects
