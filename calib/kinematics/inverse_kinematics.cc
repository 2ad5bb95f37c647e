#include "calib/kinematics/inverse_kinematics.h"

#include <cmath>
#include <random>
#include <sstream>
#include <utility>

#include <Eigen/Cholesky>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"

namespace twin {
namespace {

using Error6 = Eigen::Matrix<double, 6, 1>;
using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;

struct Attempt {
  JointVector q;
  double position_error = 0.0;
  double orientation_error = 0.0;
  int iterations = 0;
  bool converged = false;
};

// Pose error of the end pose X against the target: translation [m] and rotation vector in B
// [rad].
Error6 PoseError(const Transform& X_target, const Transform& X) {
  Error6 e;
  e.head<3>() = X_target.translation() - X.translation();
  const Eigen::AngleAxisd aa(X_target.linear() * X.linear().transpose());
  e.tail<3>() = aa.angle() * aa.axis();
  return e;
}

JointVector Clamp(const KinematicModel& model, JointVector q) {
  for (int i = 0; i < model.num_joints(); ++i) {
    q(i) = std::min(std::max(q(i), model.links[i].limits.lower), model.links[i].limits.upper);
  }
  return q;
}

// Levenberg-Marquardt step (JtJ + lambda (1 + diag JtJ)) dq = g.
JointVector LmStep(const JointMatrix& JtJ, const JointVector& g, double lambda) {
  JointMatrix A = JtJ;
  A.diagonal().array() += lambda * (1.0 + JtJ.diagonal().array());
  return A.ldlt().solve(g);
}

// LM step that holds joints resting on a limit the step would push through, so the others
// keep moving along the boundary instead of the whole step being clamped away.
JointVector ActiveSetStep(const KinematicModel& model, const JointVector& q,
                          JointMatrix JtJ, JointVector g, double lambda) {
  JointVector dq = LmStep(JtJ, g, lambda);
  const int n = model.num_joints();
  for (int pass = 0; pass < n; ++pass) {
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      const JointLimits& l = model.links[i].limits;
      const bool blocked = (q(i) <= l.lower && dq(i) < 0.0) || (q(i) >= l.upper && dq(i) > 0.0);
      if (blocked && g(i) != 0.0) {
        JtJ.row(i).setZero();
        JtJ.col(i).setZero();
        JtJ(i, i) = 1.0;
        g(i) = 0.0;
        changed = true;
      }
    }
    if (!changed) break;
    dq = LmStep(JtJ, g, lambda);
  }
  return dq;
}

// Levenberg-Marquardt on the weighted pose error from one start; `limits` clamps each iterate.
Attempt Descend(const KinematicModel& model, const Transform& X_target, JointVector q,
                const IkOptions& o, bool limits, const ChainTrig& trig) {
  const double w = o.position_only ? 0.0 : o.orientation_weight;
  auto cost = [&](const Error6& e) {
    return e.head<3>().squaredNorm() + w * w * e.tail<3>().squaredNorm();
  };
  Attempt a;
  // The frames of the current iterate, for its Jacobian: one pass over the chain gives them and
  // the end pose of the error (FramesAndEndPose).
  FrameSet frames, trial_frames;
  Error6 e = PoseError(X_target, FramesAndEndPose(model, q, &trig, &frames));
  double lambda = o.damping;
  for (a.iterations = 0; a.iterations < o.max_iterations; ++a.iterations) {
    if (e.head<3>().norm() <= o.position_tolerance &&
        (o.position_only || e.tail<3>().norm() <= o.orientation_tolerance)) {
      a.converged = true;
      break;
    }
    JointJacobian J = ManipulatorJacobian(frames);
    Error6 ew = e;
    J.bottomRows<3>() *= w;
    ew.tail<3>() *= w;
    const JointMatrix JtJ = J.transpose() * J;
    const JointVector g = J.transpose() * ew;
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      JointVector dq = limits ? ActiveSetStep(model, q, JtJ, g, lambda) : LmStep(JtJ, g, lambda);
      const double n = dq.cwiseAbs().maxCoeff();
      if (n > o.max_step) dq *= o.max_step / n;
      JointVector q_new = q + dq;
      if (limits) q_new = Clamp(model, q_new);
      const Error6 e_new =
          PoseError(X_target, FramesAndEndPose(model, q_new, &trig, &trial_frames));
      if (cost(e_new) < cost(e)) {
        q = q_new;
        e = e_new;
        std::swap(frames, trial_frames);
        lambda = std::max(lambda * 0.3, 1e-12);
        improved = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;  // stuck at a local minimum or on a limit
  }
  a.q = q;
  a.position_error = e.head<3>().norm();
  a.orientation_error = o.position_only ? 0.0 : e.tail<3>().norm();
  return a;
}

}  // namespace

void ValidateIkOptions(const IkOptions& o) {
  // No user sets these (the CLI's `ik` sets only position_only): a bad value is our bug.
  auto positive = [](double v, const char* field) {
    TWIN_REQUIRE(std::isfinite(v) && v > 0.0, std::string("IkOptions.") + field +
                                                  " must be a positive finite number, got " +
                                                  std::to_string(v));
  };
  positive(o.position_tolerance, "position_tolerance");
  positive(o.orientation_tolerance, "orientation_tolerance");
  positive(o.damping, "damping");
  positive(o.max_step, "max_step");
  positive(o.orientation_weight, "orientation_weight");
  TWIN_REQUIRE(o.max_iterations >= 1,
               "IkOptions.max_iterations must be >= 1, got " + std::to_string(o.max_iterations));
  TWIN_REQUIRE(o.random_restarts >= 0,
               "IkOptions.random_restarts must be >= 0, got " + std::to_string(o.random_restarts));
}

const char* ToString(IkStatus status) {
  switch (status) {
    case IkStatus::kSuccess: return "success";
    case IkStatus::kNotConverged: return "not_converged";
    case IkStatus::kJointLimits: return "joint_limits";
    case IkStatus::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

IkResult SolveIk(const KinematicModel& model, const Transform& X_BE_target,
                 const JointVector& q_seed, const IkOptions& options) {
  ValidateIkOptions(options);
  IkResult r;
  r.q = ZeroJoints(model);
  if (!X_BE_target.matrix().allFinite() || !q_seed.allFinite()) {
    r.status = IkStatus::kInvalidInput;
    r.reason = "target pose or seed contains a non-finite number";
    return r;
  }
  if (q_seed.size() != model.num_joints()) {
    r.status = IkStatus::kInvalidInput;
    r.reason = "seed has " + std::to_string(q_seed.size()) + " joint angles, the model " +
               std::to_string(model.num_joints());
    return r;
  }
  if (!WithinLimits(model, q_seed)) {
    r.status = IkStatus::kInvalidInput;
    r.reason = "seed is outside the joint limits";
    return r;
  }
  std::mt19937_64 rng(options.seed);
  const ChainTrig trig(model);  // alpha, beta of the links: once for all iterations
  Attempt best;
  best.position_error = best.orientation_error = INFINITY;
  auto score = [&](const Attempt& a) {
    return a.position_error + options.orientation_weight * a.orientation_error;
  };
  for (int s = 0; s <= options.random_restarts; ++s) {
    JointVector q0 = q_seed;
    if (s > 0) {
      for (int i = 0; i < model.num_joints(); ++i) {
        std::uniform_real_distribution<double> u(model.links[i].limits.lower,
                                                  model.links[i].limits.upper);
        q0(i) = u(rng);
      }
    }
    const Attempt a = Descend(model, X_BE_target, q0, options, /*limits=*/true, trig);
    r.iterations += a.iterations;
    r.starts = s + 1;
    if (a.converged) {
      best = a;
      break;
    }
    if (score(a) < score(best)) best = a;
  }
  r.q = best.q;
  r.position_error = best.position_error;
  r.orientation_error = best.orientation_error;
  if (best.converged) {
    r.status = IkStatus::kSuccess;
    return r;
  }
  // No start converged inside the limits. Tell "outside the limits" from "out of reach" by
  // solving once more without limits.
  const Attempt free = Descend(model, X_BE_target, q_seed, options, /*limits=*/false, trig);
  r.iterations += free.iterations;
  if (free.converged) {
    JointVector q = free.q;
    std::ostringstream os;
    for (int i = 0; i < model.num_joints(); ++i) {
      const JointLimits& l = model.links[i].limits;
      const double wrapped = q(i) - 2.0 * kPi * std::floor((q(i) - l.lower) / (2.0 * kPi));
      if (wrapped <= l.upper) {
        q(i) = wrapped;
      } else {
        os << (os.tellp() > 0 ? "; " : "") << "joint " << i + 1 << " at "
           << RadToDeg(q(i)) << " deg, outside its limits [" << RadToDeg(l.lower) << ", "
           << RadToDeg(l.upper) << "] deg";
      }
    }
    if (os.tellp() == 0 && WithinLimits(model, q)) {  // the limits only needed a 2 pi wrap
      r.q = q;
      r.position_error = free.position_error;
      r.orientation_error = free.orientation_error;
      r.status = IkStatus::kSuccess;
      return r;
    }
    r.status = IkStatus::kJointLimits;
    r.reason = "no solution found inside the joint limits; an unconstrained solution puts " +
               os.str();
    return r;
  }
  r.status = IkStatus::kNotConverged;
  std::ostringstream os;
  os << "no solution within tolerance after " << r.starts << " starts; best position error "
     << best.position_error * 1e3 << " mm, orientation error "
     << RadToDeg(best.orientation_error) << " deg";
  const double sigma_min = SmallestJacobianSingularValue(model, best.q);
  if (best.position_error < 1e-3 && sigma_min < 1e-2) {
    os << " (converging slowly next to a singular configuration, smallest Jacobian singular "
          "value "
       << sigma_min << ")";
  } else {
    os << " (target likely out of reach)";
  }
  r.reason = os.str();
  return r;
}

}  // namespace twin
