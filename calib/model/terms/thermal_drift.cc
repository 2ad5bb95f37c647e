#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// Thermal drift of the whole arm over the measurement session (the arm warming up as it
// works, temperature not recorded):
//   d_i, a_i (every joint link; not the tool link, robot_model.h stage 2) *= 1 + r t
// with t the measurement's time stamp [s] from the start of the session and r the growth
// rate [1/s]. Needs a time stamp.
class ThermalDrift : public ErrorTermT<ThermalDrift> {
 public:
  using ErrorTermT::ErrorTermT;

  std::string Requires(const MeasurementContext& c) const override {
    return c.has_time() ? "" : "a time stamp";
  }

  TermDriver driver() const override { return TermDriver::kClockUnbounded; }

  template <typename T>
  void ScaleLengthsT(const T* p, const MeasurementContext& c, T* s) const {
    *s *= T(1.0) + p[0] * c.time_s;
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeThermalDrift(const TermInput& in) {
  // Scale: the rate that grows the arm's reach by 1 m in an hour.
  const double scale = 1.0 / (3600.0 * NominalReach(in.nominal));
  return std::make_shared<ThermalDrift>(
      in.spec, std::vector<TermParameter>{{in.robot + ".thermal.per_second", "1/s", scale}});
}

}  // namespace twin::terms
