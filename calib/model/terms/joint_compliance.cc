#include "calib/model/terms/terms.h"

#include "calib/model/robot_model.h"

namespace twin::terms {
namespace {

// Joint compliance (an elastic transmission) of joint i:
//   q_link,i += c_i * tau_i(q_link)
// with tau_i the gravity torque about joint i of the nominal masses (RobotModel stage 3, solved
// with the configuration it changes) and c_i = 1 / k_i the compliance [rad/(N m)]. It needs no
// context: the torques follow from the configuration. A joint whose axis stays parallel to
// gravity (joint 1 of a floor-mounted arm) sees tau_i = 0, so its c_i is unidentifiable.
class JointCompliance : public ErrorTermT<JointCompliance> {
 public:
  using ErrorTermT::ErrorTermT;
  bool sags_under_gravity() const override { return true; }

  template <typename T>
  void SagT(const T* p, const T* tau, T* q) const {
    const int i = spec().joint;
    q[i] += p[0] * tau[i];
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeJointCompliance(const TermInput& in) {
  // Scale: 1 rad per typical torque, the weight of the arm at half its reach.
  double mass = 0.0;
  for (const Link& l : in.nominal.links) mass += l.inertia.mass;
  const double tau_ref = std::max(1.0, kStandardGravity * mass * 0.5 * NominalReach(in.nominal));
  return std::make_shared<JointCompliance>(
      in.spec, std::vector<TermParameter>{
                   {JointPrefix(in.robot, in.spec.joint) + ".compliance", "rad/(N m)",
                    1.0 / tau_ref}});
}

}  // namespace twin::terms
