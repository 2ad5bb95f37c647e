#include "bench/runs/kinematics_benchmark.h"

#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/model/end_point_jacobian.h"

namespace twin {
namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double MicrosecondsPerCall(int n, F&& f) {
  const auto t0 = Clock::now();
  for (int i = 0; i < n; ++i) f(i);
  return std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / n;
}

}  // namespace

int RunKinematicsBenchmark(const KinematicsBenchmarkOptions& o) {
  if (o.evaluations < 1 || o.evaluations > 10000000) {
    throw InputError("--evaluations", "expected 1 to 10000000, got " + std::to_string(o.evaluations));
  }
  const KinematicModel chain = LoadRobotModelAndWarn(o.model, o.links);
  const RobotModel model = MakeRobotModel(chain);
  std::mt19937_64 rng(1);
  std::vector<MeasurementContext> contexts;
  for (int k = 0; k < 256; ++k) {
    JointVector q(chain.num_joints());
    for (int i = 0; i < q.size(); ++i) {
      q(i) = std::uniform_real_distribution<double>(chain.links[i].limits.lower,
                                                    chain.links[i].limits.upper)(rng);
    }
    contexts.push_back(ContextOf(q));
  }
  const Eigen::VectorXd p = GetParameters(model);
  Vector3 point;
  PointJacobian J;
  double sink = 0.0;
  const int n = o.evaluations;
  const double fk = MicrosecondsPerCall(n, [&](int i) {
    sink += EndPose(chain, contexts[i % 256].q).translation().x();
  });
  const double analytic = MicrosecondsPerCall(n, [&](int i) {
    EndPointJacobian(model, p.data(), contexts[i % 256], &point, &J);
    sink += J(0, 0);
  });
  const double autodiff = MicrosecondsPerCall(n, [&](int i) {
    EndPointJacobianAutodiff(model, p.data(), contexts[i % 256], &point, &J);
    sink += J(0, 0);
  });
  std::printf("%s: %d joints, %d parameters, %d evaluations each\n", chain.name.c_str(),
              chain.num_joints(), model.num_parameters(), n);
  std::printf("forward kinematics (end pose)          %8.3f us\n", fk);
  std::printf("end-point Jacobian, analytic           %8.3f us\n", analytic);
  std::printf("end-point Jacobian, autodiff (Jet<%d>)  %8.3f us  (%.1fx the analytic)\n",
              kJetStride, autodiff, autodiff / analytic);
  if (sink == 1234.5) std::printf(" ");  // keeps the loops from being optimized away
  return 0;
}

}  // namespace twin
