#include "calib/identification/linearized_identification.h"

#include <cmath>

#include <Eigen/Cholesky>

#include "calib/common/errors.h"

namespace twin {
namespace {

using Square = Eigen::MatrixXd;

// E and the (optionally profiled) Phi of `model`, with each axis refitted by FitLine.
struct Linearization {
  Eigen::VectorXd E;
  Eigen::MatrixXd Phi;
};

Linearization Linearize(const KinematicModel& model, const std::vector<AxisSample>& samples,
                        bool profile) {
  std::vector<Vector3> directions;
  for (const Line3& l : FitAxes(model, samples)) directions.push_back(l.direction);
  MisalignedErrorStack stack = StackMisalignedErrors(model, samples, directions);
  Linearization lin;
  lin.Phi = profile ? ProfiledPhi(stack) : stack.Phi;
  lin.E = std::move(stack.E);
  return lin;
}

// eps of eq. 47 at `model`: |E| with refitted axes.
double Eps(const KinematicModel& model, const std::vector<AxisSample>& samples) {
  std::vector<Vector3> directions;
  for (const Line3& l : FitAxes(model, samples)) directions.push_back(l.direction);
  double sum = 0.0;
  const auto points = AxisPoints(model, samples);
  for (size_t k = 0; k < points.size(); ++k) {
    for (size_t i = 0; i < points[k].size(); ++i) {
      for (size_t j = i + 1; j < points[k].size(); ++j) {
        sum += MisalignedError(directions[k], points[k][i], points[k][j]).squaredNorm();
      }
    }
  }
  return std::sqrt(sum);
}

}  // namespace

void ValidateLinearizedIdentificationOptions(const LinearizedIdentificationOptions& o) {
  // No user sets these (the scenario and CLI reach none of them): a bad value is our bug.
  auto fail = [](const char* field, double v, const char* expected) {
    FailPrecondition("valid LinearizedIdentificationOptions",
                     std::string("LinearizedIdentificationOptions.") + field + " " + expected +
                         ", got " + std::to_string(v),
                     __FILE__, __LINE__);
  };
  if (o.max_iterations < 1) fail("max_iterations", o.max_iterations, "must be >= 1");
  if (!(std::isfinite(o.initial_lambda) && o.initial_lambda > 0.0)) {
    fail("initial_lambda", o.initial_lambda, "must be a positive finite number");
  }
  if (!(std::isfinite(o.lambda_factor) && o.lambda_factor > 1.0)) {
    fail("lambda_factor", o.lambda_factor, "must be a finite number > 1");
  }
  if (!(std::isfinite(o.max_lambda) && o.max_lambda > o.initial_lambda)) {
    fail("max_lambda", o.max_lambda, "must be finite and > initial_lambda");
  }
  if (!(o.min_relative_decrease >= 0.0 && o.min_relative_decrease < 1.0)) {
    fail("min_relative_decrease", o.min_relative_decrease, "must be in [0, 1)");
  }
  if (!(o.rank_tolerance > 0.0 && o.rank_tolerance < 1.0)) {
    fail("rank_tolerance", o.rank_tolerance, "must be in (0, 1)");
  }
}

const char* ToString(LinearizedIdentificationStatus status) {
  switch (status) {
    case LinearizedIdentificationStatus::kConverged: return "converged";
    case LinearizedIdentificationStatus::kMaxIterations: return "max_iterations";
    case LinearizedIdentificationStatus::kSkipped: return "skipped";
  }
  return "unknown";
}

std::vector<ParameterVector> LineConstraintInvariants(const KinematicModel& model) {
  const ParameterVector phi = GetParameters(model);
  const int n = model.num_parameters();
  ParameterVector rotation = ParameterVector::Zero(n), translation = ParameterVector::Zero(n),
                  scale = ParameterVector::Zero(n);
  rotation(ParameterIndex(1, DhParameter::kTheta)) = 1.0;
  translation(ParameterIndex(1, DhParameter::kD)) = 1.0;
  for (int i = 0; i < n; ++i) {
    if (IsLengthParameter(i)) scale(i) = phi(i);
  }
  return {rotation, translation, scale};
}

LinearizedIdentificationResult IdentifyFromOpticalAxes(
    const KinematicModel& nominal, const std::vector<AxisSample>& samples,
    const LinearizedIdentificationOptions& options) {
  ValidateLinearizedIdentificationOptions(options);
  ValidateAxisSamples(samples);
  LinearizedIdentificationResult res;
  const ParameterVector phi0 = GetParameters(nominal);

  // Identifiable subspace from the nominal model (held fixed: the gauge of the solution).
  Linearization lin = Linearize(nominal, samples, options.profile_axis_directions);
  res.observability = AnalyseObservability(lin.Phi, nominal, options.rank_tolerance,
                                           LineConstraintInvariants(nominal));
  const Eigen::VectorXd& S = res.observability.column_scale;
  const int n = nominal.num_parameters();
  const Eigen::MatrixXd& V = res.observability.identifiable_basis;  // 35 x rank
  const Square P = V * V.transpose();  // projector onto the identifiable subspace

  KinematicModel model = nominal;
  double eps = Eps(model, samples);
  res.eps_history.push_back(eps);
  res.mean_misaligned_error_before = MeanMisalignedErrorNorm(nominal, samples);
  double lambda = options.initial_lambda;
  bool relinearize = false;
  res.status = LinearizedIdentificationStatus::kMaxIterations;
  res.reason = "reached max_iterations = " + std::to_string(options.max_iterations);
  while (res.iterations < options.max_iterations) {
    if (relinearize) lin = Linearize(model, samples, options.profile_axis_directions);
    relinearize = false;
    // Eq. 48 in scaled coordinates x (dphi = S x), restricted to x = P x:
    // (P A^T A P + lambda I) x = P A^T E has its solution in range(P).
    const Eigen::MatrixXd A = lin.Phi * S.asDiagonal();
    const Square G = P * (A.transpose() * A) * P;
    const ParameterVector g = P * (A.transpose() * lin.E);
    const ParameterVector x = (G + lambda * Square::Identity(n, n)).ldlt().solve(g);
    const ParameterVector dphi = S.cwiseProduct(P * x);  // P x removes round-off leakage
    ++res.iterations;
    const KinematicModel candidate = WithParameters(model, GetParameters(model) + dphi);
    const double eps_new = Eps(candidate, samples);
    if (std::isfinite(eps_new) && eps_new < eps * (1.0 - options.min_relative_decrease)) {
      model = candidate;
      eps = eps_new;
      res.eps_history.push_back(eps);
      lambda /= options.lambda_factor;  // eq. 49, improvement
      relinearize = true;
    } else {
      lambda *= options.lambda_factor;  // eq. 49, no improvement (typeset as /h in the paper)
      if (lambda > options.max_lambda) {
        res.status = LinearizedIdentificationStatus::kConverged;
        res.reason = "eps stopped decreasing (lambda above max_lambda)";
        break;
      }
    }
  }
  res.final_lambda = lambda;
  res.model = model;
  res.correction = GetParameters(model) - phi0;
  res.mean_misaligned_error_after = MeanMisalignedErrorNorm(model, samples);
  return res;
}

}  // namespace twin
