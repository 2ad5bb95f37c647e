#include "calib/model/robot_model.h"

#include "calib/common/errors.h"
#include "calib/model/parameters.h"

namespace twin {

RobotModel MakeRobotModel(const KinematicModel& chain, const Vector3& gravity_B) {
  RobotModel m;
  m.chain = chain;
  m.gravity_B = gravity_B.normalized();
  return m;
}

RobotModel WithTerm(const RobotModel& model, std::shared_ptr<const ErrorTerm> term) {
  for (const auto& t : model.terms) {
    if (t->spec().type == term->spec().type && t->spec().joint == term->spec().joint &&
        t->spec().orders == term->spec().orders) {
      throw InputError(model.name(), "the model already has " + TermLabel(term->spec()));
    }
  }
  RobotModel out = model;
  const int n = static_cast<int>(term->parameters().size());
  out.term_values.conservativeResize(model.term_values.size() + n);
  out.term_values.tail(n).setZero();
  out.terms.push_back(std::move(term));
  return out;
}

namespace {

// Calls f(term, offset into term_values) for each term whose dormant parameters are asleep.
template <typename F>
void ForEachDormantTermAtZero(const RobotModel& model, F f) {
  int offset = 0;
  for (const auto& t : model.terms) {
    const int n = static_cast<int>(t->parameters().size());
    if (t->has_dormant_parameters() &&
        model.term_values.segment(offset, t->amplitude_parameters()).isZero(0.0)) {
      f(*t, offset);
    }
    offset += n;
  }
}

}  // namespace

bool HasDormantTermsAtZero(const RobotModel& model) {
  bool any = false;
  ForEachDormantTermAtZero(model, [&](const ErrorTerm&, int) { any = true; });
  return any;
}

RobotModel WithDormantTermsFrom(const RobotModel& model, const RobotModel& solved) {
  bool same = solved.terms.size() == model.terms.size() &&
              solved.term_values.size() == model.term_values.size();
  for (std::size_t i = 0; same && i < model.terms.size(); ++i) {
    const TermSpec& a = model.terms[i]->spec();
    const TermSpec& b = solved.terms[i]->spec();
    same = a.type == b.type && a.joint == b.joint && a.orders == b.orders;
  }
  // `solved` is a fit started from `model` (our own code), so its terms are the same.
  TWIN_REQUIRE(same, "the solved model of " + model.name() + " has other terms than the model");
  RobotModel out = model;
  ForEachDormantTermAtZero(model, [&](const ErrorTerm& t, int offset) {
    const int n = static_cast<int>(t.parameters().size());
    out.term_values.segment(offset, n) = solved.term_values.segment(offset, n);
  });
  return out;
}

Eigen::VectorXd GetParameters(const RobotModel& model) {
  Eigen::VectorXd p(model.num_parameters());
  p << GetParameters(model.chain), model.term_values;
  return p;
}

RobotModel WithParameters(const RobotModel& model, const Eigen::VectorXd& params) {
  TWIN_REQUIRE(params.size() == model.num_parameters(),
               std::to_string(params.size()) + " parameters for a model of " +
                   std::to_string(model.num_parameters()));
  RobotModel out = model;
  const int g = model.chain.num_parameters();
  out.chain = WithParameters(model.chain, params.head(g));
  out.term_values = params.tail(params.size() - g);
  return out;
}

Transform EndPose(const RobotModel& model, const MeasurementContext& context) {
  TWIN_REQUIRE(context.q.size() == model.chain.num_joints(),
               std::to_string(context.q.size()) + " joint angles for a " +
                   std::to_string(model.chain.num_joints()) + "-joint chain");
  const Eigen::VectorXd p = GetParameters(model);
  return ToTransform(RobotEndPoseT<double>(model, p.data(), context));
}

Eigen::VectorXd GravityTorques(const RobotModel& model, const JointVector& q_link) {
  const FrameSet f = ForwardKinematics(model.chain, q_link);
  std::array<RigidT<double>, kMaxJoints + 2> X;
  for (int i = 0; i <= model.chain.num_links(); ++i) {
    X[i] = {f.X_BL[i].linear(), f.X_BL[i].translation()};
  }
  Eigen::VectorXd tau(model.chain.num_joints());
  GravityTorquesT<double>(model.chain, X.data(), model.gravity_B, model.gravity, tau.data());
  return tau;
}

std::string MissingContext(const RobotModel& model, const MeasurementContext& context) {
  for (const auto& t : model.terms) {
    const std::string need = t->Requires(context);
    if (!need.empty()) return TermLabel(t->spec()) + ": needs " + need;
  }
  return "";
}

}  // namespace twin
