#include "calib/identification/nonlinear_identification.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <ceres/ceres.h>

#include "calib/measurements/optical_axis_residual.h"
#include "calib/measurements/optical_axis_set.h"

#include "calib/common/errors.h"
#include "calib/diagnosis/statistics.h"

namespace twin {

void ValidateNonlinearIdentificationOptions(const NonlinearIdentificationOptions& o) {
  // No user sets these (the scenario and CLI reach none of them): a bad value is our bug.
  auto fail = [](const char* field, double v, const char* expected) {
    FailPrecondition("valid NonlinearIdentificationOptions",
                     std::string("NonlinearIdentificationOptions.") + field + " " + expected +
                         ", got " + std::to_string(v),
                     __FILE__, __LINE__);
  };
  if (o.max_iterations < 1) fail("max_iterations", o.max_iterations, "must be >= 1");
  if (o.relinearize_passes < 0) fail("relinearize_passes", o.relinearize_passes, "must be >= 0");
  if (!(o.function_tolerance > 0.0 && o.function_tolerance < 1.0)) {
    fail("function_tolerance", o.function_tolerance, "must be in (0, 1)");
  }
  if (!(std::isfinite(o.gradient_tolerance) && o.gradient_tolerance > 0.0)) {
    fail("gradient_tolerance", o.gradient_tolerance, "must be a positive finite number");
  }
  if (!(std::isfinite(o.parameter_tolerance) && o.parameter_tolerance > 0.0)) {
    fail("parameter_tolerance", o.parameter_tolerance, "must be a positive finite number");
  }
  if (!(o.rank_tolerance > 0.0 && o.rank_tolerance < 1.0)) {
    fail("rank_tolerance", o.rank_tolerance, "must be in (0, 1)");
  }
  if (o.loss != NonlinearLoss::kNone && o.loss != NonlinearLoss::kHuber) {
    fail("loss", static_cast<double>(o.loss), "must be kNone or kHuber");
  }
  if (o.loss == NonlinearLoss::kHuber &&
      !(std::isfinite(o.huber_scale) && o.huber_scale > 0.0)) {
    fail("huber_scale", o.huber_scale, "must be a positive finite number [m] with kHuber");
  }
}

const char* ToString(NonlinearIdentificationStatus status) {
  switch (status) {
    case NonlinearIdentificationStatus::kConverged: return "converged";
    case NonlinearIdentificationStatus::kMaxIterations: return "max_iterations";
    case NonlinearIdentificationStatus::kFailed: return "failed";
  }
  return "unknown";
}

Vector3 AxisResidual(const KinematicModel& model, const ParameterVector& phi,
                     const JointVector& q, const Vector3& point, const Vector3& direction) {
  const RobotModel m = MakeRobotModel(model);
  const double weight = 1.0;
  const Vector3 mu = direction.normalized();
  Eigen::Matrix<double, 3, 2> N;
  N.col(0) = mu.unitOrthogonal();
  N.col(1) = mu.cross(N.col(0));
  const OpticalAxisLine f{Vector3::Zero(), point, N, weight};
  const Vector3 p = RobotEndPoseT<double>(m, phi.data(), ContextOf(q)).p;
  const double s[2] = {0.0, 0.0};
  Vector3 r;
  f(p.data(), s, mu.data(), r.data());
  return r;
}

namespace {

// The measurement set's options as IdentifyNonlinear and NonlinearIdentifiability build them.
OpticalAxisSetOptions SetOptionsFor(const NonlinearIdentificationOptions& options) {
  OpticalAxisSetOptions set_options;
  set_options.use_depth = options.use_depth;
  set_options.use_sample_sigmas = options.use_sample_sigmas;
  // A first guess of sigma_perpendicular / sigma_depth: ~0.02 mm of servo residual against
  // ~0.1 mm of depth from a small board (DESIGN.md corner accuracy); re-estimated by the
  // engine's variance components unless a weight is given.
  if (options.depth_weight > 0.0) {
    set_options.sigma_depth = set_options.sigma_perpendicular / options.depth_weight;
  }
  if (options.loss == NonlinearLoss::kHuber) set_options.huber_scale = options.huber_scale;
  return set_options;
}

}  // namespace

ObservabilityReport NonlinearIdentifiability(const KinematicModel& nominal,
                                             const std::vector<AxisSample>& samples,
                                             const NonlinearIdentificationOptions& options) {
  ValidateNonlinearIdentificationOptions(options);
  ValidateAxisSamples(samples);
  OpticalAxisSet set(samples, SetOptionsFor(options));
  IdentificationOptions io;
  io.rank_tolerance = options.rank_tolerance;
  io.estimate_group_weights = options.depth_weight <= 0.0;
  return AnalyseIdentifiability(MakeRobotModel(nominal), {&set}, io);
}

NonlinearIdentificationResult IdentifyNonlinear(const KinematicModel& nominal,
                                                const std::vector<AxisSample>& samples,
                                                const NonlinearIdentificationOptions& options) {
  ValidateNonlinearIdentificationOptions(options);
  ValidateAxisSamples(samples);
  NonlinearIdentificationResult res;
  res.model = nominal;
  res.correction = ParameterVector::Zero(nominal.num_parameters());

  OpticalAxisSet set(samples, SetOptionsFor(options));

  IdentificationOptions io;
  io.max_iterations = options.max_iterations;
  io.function_tolerance = options.function_tolerance;
  io.gradient_tolerance = options.gradient_tolerance;
  io.parameter_tolerance = options.parameter_tolerance;
  io.rank_tolerance = options.rank_tolerance;
  io.estimate_group_weights = options.depth_weight <= 0.0;
  const RobotModel start = MakeRobotModel(nominal);
  res.engine = Identify(start, {&set}, io);
  const double rms_nominal = res.engine.sets[0].rms_before;
  for (int pass = 0; pass < options.relinearize_passes; ++pass) {
    const IdentificationResult& last = res.engine;
    // Within 0.1 um (a noise-free fit) there is nothing left for another pass to reach.
    if (last.status == IdentificationStatus::kFailed || last.sets[0].rms_after < 1e-7) break;
    IdentificationResult again = Identify(last.model, {&set}, io);
    if (again.status == IdentificationStatus::kFailed || again.redundancy < 1) break;
    const int added = again.observability.rank - last.observability.rank;
    const double before = last.sets[0].rms_after, after = again.sets[0].rms_after;
    if (added < 0 || !(after < before)) break;
    if (added == 0 && !(after < 0.99 * before)) break;  // the linearization has settled
    if (added > 0) {
      // Directions that are null at the nominal model's symmetries (exactly parallel or
      // perpendicular axes) but not at the solution: kept only when the data need them, the
      // drop in the sum of squares against chi-square with `added` degrees of freedom at
      // 0.1 % (each new direction fits about one unit of it from noise alone).
      const double stat = again.redundancy * (before * before - after * after) / (after * after);
      if (!(stats::ChiSquareUpperTail(stat, added) < 1e-3)) break;
    }
    res.engine = std::move(again);
    ++res.passes;
  }
  if (res.passes > 1) {
    // The sets were re-initialized at the last start: lines and weights are that pass's.
    res.engine.correction = GetParameters(res.engine.model) - GetParameters(start);
  }
  const IdentificationResult& r = res.engine;

  res.observability = r.observability;
  res.depth_used = set.depth_used();
  res.depth_weight = set.depth_used() ? set.depth_weight() / set.perpendicular_weight() : 0.0;
  res.rms_distance_before = rms_nominal;
  res.axes = set.initial_lines();
  res.rms_distance_after = res.rms_distance_before;
  res.z = r.z;
  res.brief_report = r.brief_report;
  res.reason = r.reason;
  res.iterations = r.iterations;
  switch (r.status) {
    case IdentificationStatus::kConverged: res.status = NonlinearIdentificationStatus::kConverged; break;
    case IdentificationStatus::kMaxIterations:
      res.status = NonlinearIdentificationStatus::kMaxIterations;
      break;
    case IdentificationStatus::kFailed: res.status = NonlinearIdentificationStatus::kFailed; break;
  }
  if (res.status == NonlinearIdentificationStatus::kFailed) return res;
  res.correction = r.correction.head(nominal.num_parameters());
  res.model = r.model.chain;
  res.axes = set.lines();
  res.rms_distance_after = r.sets[0].rms_after;
  if (res.depth_used) res.rms_depth_residual = set.DepthRms(r.model);
  const ParameterVector v = LineConstraintInvariants(nominal).back();
  res.scale = 1.0 + v.dot(res.correction) / v.squaredNorm();
  return res;
}

}  // namespace twin
