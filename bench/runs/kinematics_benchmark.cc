#include "bench/runs/kinematics_benchmark.h"

#include <chrono>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/kinematics/spherical_wrist_ik.h"
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

// Inverse kinematics of the end poses at `contexts`' joints: the iterative solver from a
// seed elsewhere in the joint space (the next context's joints), and the closed form of a
// spherical-wrist arm (all solutions; the nearest inside the limits) where the model has one.
void PrintInverseKinematics(const KinematicModel& chain,
                            const std::vector<MeasurementContext>& contexts, int n,
                            double* sink) {
  const int m = static_cast<int>(contexts.size());
  std::vector<Transform> targets;
  for (const MeasurementContext& c : contexts) targets.push_back(EndPose(chain, c.q));
  long iterations = 0;
  int solved = 0;
  const double iterative = MicrosecondsPerCall(n, [&](int i) {
    const IkResult r = SolveIk(chain, targets[i % m], contexts[(i + 1) % m].q);
    iterations += r.iterations;
    solved += r.status == IkStatus::kSuccess;
    *sink += r.q(0);
  });
  std::printf("inverse kinematics, iterative          %8.3f us  (%.1f iterations a solve, %d of "
              "%d solved)\n",
              iterative, static_cast<double>(iterations) / n, solved, n);
  std::string why;
  const std::optional<SphericalWristIk> ik = SphericalWristIk::For(chain, &why);
  if (!ik) {
    std::printf("inverse kinematics, closed form        not applicable (%s)\n", why.c_str());
    return;
  }
  long solutions = 0;
  const double all = MicrosecondsPerCall(n, [&](int i) {
    const std::vector<JointVector> s = ik->Solve(targets[i % m]);
    solutions += static_cast<long>(s.size());
    *sink += s.empty() ? 0.0 : s[0](0);
  });
  int fallbacks = 0;
  const double nearest = MicrosecondsPerCall(n, [&](int i) {
    const IkResult r = SolveIkSphericalWrist(chain, targets[i % m], contexts[(i + 1) % m].q);
    fallbacks += r.iterations > 0;
    *sink += r.q(0);
  });
  std::printf("inverse kinematics, closed form        %8.3f us  (all %.1f solutions)\n", all,
              static_cast<double>(solutions) / n);
  std::printf("  SolveIkSphericalWrist (the drop-in)  %8.3f us  (%.1fx the iterative; nearest "
              "inside the limits, %d of %d fell back to the iterative)\n",
              nearest, iterative / nearest, fallbacks, n);
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
  PrintInverseKinematics(chain, contexts, std::max(1, n / 10), &sink);
  if (sink == 1234.5) std::printf(" ");  // keeps the loops from being optimized away
  return 0;
}

}  // namespace twin
