#include <cmath>

#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// Transmission error of joint i (a periodic gear error, e.g. order 1 for an eccentric output,
// 2 for an elliptic harmonic drive), for each order h of the term:
//   q_link,i += s_ih sin(h q_i) + c_ih cos(h q_i)
// with q_i the joint reading [rad] and s_ih, c_ih [rad] its parameters (an amplitude A and
// phase phi give s = A cos phi, c = A sin phi). Needs only the readings.
class TransmissionError : public ErrorTermT<TransmissionError> {
 public:
  using ErrorTermT::ErrorTermT;

  template <typename T>
  void OffsetJointsT(const T* p, const MeasurementContext& c, T* q) const {
    const int i = spec().joint;
    const double qi = c.q(i);
    for (size_t k = 0; k < spec().orders.size(); ++k) {
      const double h = spec().orders[k];
      q[i] += p[2 * k] * std::sin(h * qi) + p[2 * k + 1] * std::cos(h * qi);
    }
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeTransmissionError(const TermInput& in) {
  std::vector<TermParameter> params;
  const std::string prefix = JointPrefix(in.robot, in.spec.joint);
  for (int h : in.spec.orders) {
    const std::string name = prefix + ".harmonic" + std::to_string(h);
    params.push_back({name + ".sin", "rad", 1.0});
    params.push_back({name + ".cos", "rad", 1.0});
  }
  return std::make_shared<TransmissionError>(in.spec, params);
}

}  // namespace twin::terms
