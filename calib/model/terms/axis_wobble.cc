#include <cmath>

#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// Wobble of joint i's axis (bearing runout): the axis tilts as a periodic function of its own
// reading q_i. In the frame X_BL[i] (joint i's axis z, before it turns), for each order h:
//   w_x += a_h sin(h q_i) + b_h cos(h q_i),   w_y += c_h sin(h q_i) + d_h cos(h q_i)
// [rad] (stage 5). At order 1 the part of the tilt that turns with the link (w = RotZ(q) u) is
// a fixed tilt of the link, which the geometry already has: of order 1's four parameters two
// combinations are the geometry's, and the identification treats them as such.
class AxisWobble : public ErrorTermT<AxisWobble> {
 public:
  using ErrorTermT::ErrorTermT;
  bool deflects_axes() const override { return true; }

  template <typename T>
  void DeflectAxesT(const T* p, const MeasurementContext& c, const DeflectionInputT<T>&,
                    T* w) const {
    const int i = spec().joint;
    const double qi = c.q(i);
    for (size_t k = 0; k < spec().orders.size(); ++k) {
      const double h = spec().orders[k];
      const double s = std::sin(h * qi), co = std::cos(h * qi);
      w[3 * i] += p[4 * k] * s + p[4 * k + 1] * co;
      w[3 * i + 1] += p[4 * k + 2] * s + p[4 * k + 3] * co;
    }
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeAxisWobble(const TermInput& in) {
  std::vector<TermParameter> params;
  const std::string prefix = JointPrefix(in.robot, in.spec.joint) + ".wobble";
  for (int h : in.spec.orders) {
    const std::string name = prefix + std::to_string(h);
    params.push_back({name + ".x_sin", "rad", 1.0});
    params.push_back({name + ".x_cos", "rad", 1.0});
    params.push_back({name + ".y_sin", "rad", 1.0});
    params.push_back({name + ".y_cos", "rad", 1.0});
  }
  return std::make_shared<AxisWobble>(in.spec, params);
}

}  // namespace twin::terms
