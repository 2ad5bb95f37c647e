#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// Backlash / hysteresis of joint i (a dead band the link takes up on the side it was last
// driven from):
//   q_link,i += b_i * a_i
// with a_i = +1 or -1 the sign of joint i's last motion before the reading (0 when it did not
// move) and b_i [rad] the parameter (minus half the dead band when the link lags the motor).
// Needs the approach directions.
class Backlash : public ErrorTermT<Backlash> {
 public:
  using ErrorTermT::ErrorTermT;

  std::string Requires(const MeasurementContext& c) const override {
    return c.approach.size() == c.q.size() ? "" : "the approach direction of every joint";
  }

  template <typename T>
  void OffsetJointsT(const T* p, const MeasurementContext& c, T* q) const {
    const int i = spec().joint;
    q[i] += p[0] * c.approach_of(i);
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeBacklash(const TermInput& in) {
  return std::make_shared<Backlash>(
      in.spec,
      std::vector<TermParameter>{{JointPrefix(in.robot, in.spec.joint) + ".backlash", "rad", 1.0}});
}

}  // namespace twin::terms
