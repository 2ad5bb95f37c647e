#include "calib/model/terms/terms.h"

#include "calib/model/robot_model.h"

namespace twin::terms {
namespace {

// Joint compliance (an elastic transmission) of joint i, in a model with masses:
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

// Joint compliance of joint i in a model without masses: the gravity torque comes from lumped
// masses identified with it, m_k at the points P_k LumpsBeyond gives; what the data identify is
// the compliance times each lump's weight, a_k = c_i m_k g [rad/m]:
//   q_link,i += sum_k a_k z_i . ((P_k - o_i) x g_B)
// (stage 5, the z component in frame X_BL[i]; one pass from the frames of stages 1-3 instead
// of stage 3's iteration: the sag changes its own torque by c dtau/dq ~ 1e-3 of itself).
class LumpedJointCompliance : public ErrorTermT<LumpedJointCompliance> {
 public:
  LumpedJointCompliance(TermSpec spec, std::vector<TermParameter> parameters, Lumps lumps,
                        int num_joints)
      : ErrorTermT(std::move(spec), std::move(parameters)),
        lumps_(std::move(lumps)),
        num_joints_(num_joints) {}
  bool deflects_axes() const override { return true; }

  template <typename T>
  void DeflectAxesT(const T* p, const MeasurementContext&, const DeflectionInputT<T>& in,
                    T* w) const {
    const int i = spec().joint;
    const RigidT<T>& X = in.X_BL[i];
    const Vec3T<T> z = X.R.col(2);
    for (size_t k = 0; k < lumps_.points.size(); ++k) {
      const Vec3T<T> r = LumpPoint(in, lumps_.points[k], num_joints_) - X.p;
      w[3 * i + 2] += p[k] * z.dot(r.cross(in.g_B.template cast<T>()));
    }
  }

 private:
  Lumps lumps_;
  int num_joints_;
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeJointCompliance(const TermInput& in) {
  if (!HasMasses(in.nominal)) {
    // Scale: 1 rad per lever of the arm's reach.
    Lumps lumps = LumpsBeyond(in.nominal, in.spec.joint);
    std::vector<TermParameter> params;
    const std::string prefix = JointPrefix(in.robot, in.spec.joint) + ".compliance";
    for (const std::string& name : lumps.names) {
      params.push_back({prefix + "_weight_at_" + name, "rad/m", 1.0 / NominalReach(in.nominal)});
    }
    return std::make_shared<LumpedJointCompliance>(in.spec, params, std::move(lumps),
                                                   in.nominal.num_joints());
  }
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
