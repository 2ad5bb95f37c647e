#include <cmath>

#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// The arm warming up over the session as a first-order lag (a cold start; temperature not
// recorded): its lengths approach a final growth g with time constant tau,
//   d_i, a_i (every link, the tool link too) *= 1 + g (1 - exp(-t / tau)),
// with t the measurement's time stamp [s] from the start of the session. tau is the term's
// order, in minutes (a candidate per time constant: the growth g is linear, tau is not, and a
// zero g would leave tau without a gradient). For tau much longer than the session it is the
// linear thermal_drift; for a shorter one it levels off, as a warming arm does. Needs a time
// stamp.
class ThermalWarmup : public ErrorTermT<ThermalWarmup> {
 public:
  ThermalWarmup(TermSpec spec, std::vector<TermParameter> parameters)
      : ErrorTermT(std::move(spec), std::move(parameters)),
        tau_s_(60.0 * this->spec().orders.at(0)) {}

  std::string Requires(const MeasurementContext& c) const override {
    return c.has_time() ? "" : "a time stamp";
  }

  template <typename T>
  void ScaleLengthsT(const T* p, const MeasurementContext& c, T* s) const {
    *s *= T(1.0) - p[0] * std::expm1(-std::max(0.0, c.time_s) / tau_s_);
  }

 private:
  double tau_s_;
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeThermalWarmup(const TermInput& in) {
  // Scale: the final growth that lengthens the arm's reach by 1 mm.
  const double scale = 1.0 / NominalReach(in.nominal);
  return std::make_shared<ThermalWarmup>(
      in.spec, std::vector<TermParameter>{{in.robot + ".thermal.warmup_growth", "1", scale}});
}

}  // namespace twin::terms
