#include <cmath>

#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// The arm warming up over the session as a first-order lag (a cold start; temperature not
// recorded): its lengths approach a final growth g with time constant tau,
//   d_i, a_i *= 1 + g (1 - exp(-t / tau))  (every joint link; not the tool link: robot_model.h),
//   tau = tau0 exp(l),
// with t the measurement's time stamp [s] from the start of the session, tau0 the term's
// order in minutes (where the time constant starts) and l its estimated log-ratio. For tau much
// longer than the session it is the linear thermal_drift; for a shorter one it levels off, as
// a warming arm does. While g = 0, l has no gradient: model discovery screens the term at its
// order and estimates l from a start at the first solution's g (ScoreCandidate, "restarted").
// Needs a time stamp.
class ThermalWarmup : public ErrorTermT<ThermalWarmup> {
 public:
  ThermalWarmup(TermSpec spec, std::vector<TermParameter> parameters)
      : ErrorTermT(std::move(spec), std::move(parameters)),
        tau0_s_(60.0 * this->spec().orders.at(0)) {}

  std::string Requires(const MeasurementContext& c) const override {
    return c.has_time() ? "" : "a time stamp";
  }
  TermDriver driver() const override { return TermDriver::kClockLevelling; }
  int amplitude_parameters() const override { return 1; }  // the growth; l shapes it

  // The growth reached by the session's end, g (1 - exp(-u)) with u = T / tau: for a time
  // constant long against the session g and l trade off (only about g / tau is seen), while
  // this is what the data measure. d/dg = 1 - exp(-u), d/dl = -g u exp(-u).
  Eigen::VectorXd SizeMeasures(const double* p, double session_s,
                               Eigen::MatrixXd* jacobian) const override {
    if (!(session_s > 0.0)) return ErrorTerm::SizeMeasures(p, session_s, jacobian);
    const double u = session_s * std::exp(-p[1]) / tau0_s_;
    *jacobian = Eigen::MatrixXd(1, 2);
    (*jacobian)(0, 0) = -std::expm1(-u);
    (*jacobian)(0, 1) = -p[0] * u * std::exp(-u);
    return Eigen::VectorXd::Constant(1, -p[0] * std::expm1(-u));
  }

  template <typename T>
  void ScaleLengthsT(const T* p, const MeasurementContext& c, T* s) const {
    using std::exp;
    using std::expm1;
    const T rate = exp(-p[1]) / tau0_s_;  // 1 / tau
    *s *= T(1.0) - p[0] * expm1(-std::max(0.0, c.time_s) * rate);
  }

 private:
  double tau0_s_;
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeThermalWarmup(const TermInput& in) {
  // Scales: the final growth that lengthens the arm's reach by 1 mm; a log-ratio of 1 (tau
  // times e).
  const double scale = 1.0 / NominalReach(in.nominal);
  return std::make_shared<ThermalWarmup>(
      in.spec, std::vector<TermParameter>{{in.robot + ".thermal.warmup_growth", "1", scale},
                                          {in.robot + ".thermal.warmup_log_tau_ratio", "1", 1.0}});
}

}  // namespace twin::terms
