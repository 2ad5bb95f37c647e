#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// Thermal growth of the whole arm with a recorded temperature change:
//   d_i, a_i (every joint link; not the tool link, robot_model.h stage 2) *= 1 + k dT
// with dT the measurement's temperature change from the nominal model's reference [K] and k
// the effective expansion coefficient [1/K] (steel 1.2e-5, aluminium 2.3e-5). Needs a
// temperature. With dT the same for every measurement, k dT is a uniform scale of the arm,
// which the geometric lengths already carry: k is then not separable from them.
class ThermalGrowth : public ErrorTermT<ThermalGrowth> {
 public:
  using ErrorTermT::ErrorTermT;

  std::string Requires(const MeasurementContext& c) const override {
    return c.has_temperature() ? "" : "a temperature change";
  }

  template <typename T>
  void ScaleLengthsT(const T* p, const MeasurementContext& c, T* s) const {
    *s *= T(1.0) + p[0] * c.temperature_delta_K;
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeThermalGrowth(const TermInput& in) {
  // Scale: the coefficient that grows the arm's reach by 1 m over 10 K (a unit scaled change
  // moves the tool by about as much as 1 rad of joint angle on a 1 m arm).
  const double scale = 1.0 / (10.0 * NominalReach(in.nominal));
  return std::make_shared<ThermalGrowth>(
      in.spec, std::vector<TermParameter>{{in.robot + ".thermal.per_kelvin", "1/K", scale}});
}

}  // namespace twin::terms
