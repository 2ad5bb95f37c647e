#include "bench/runs/planning_benchmark.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "bench/io/calibration_config.h"
#include "bench/io/scenario.h"
#include "calib/common/errors.h"
#include "calib/planning/pose_planner.h"
#include "calib/procedures/optical_axis_procedure.h"

namespace twin {
namespace {

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

}  // namespace

int RunPlanningBenchmark(const PlanningBenchmarkOptions& o) {
  const Scenario sc = LoadScenario(o.scenario);
  CalibrationConfig config = ParseCalibrationConfig(sc);
  if (o.threads < 0) throw InputError("--threads", "expected >= 0");
  PosePlannerOptions p = config.options.planner;
  p.threads = o.threads;
  const CellKnowledge& k = config.knowledge;
  std::printf("planning benchmark: %s, %d axes x %d positions, swarm %d, %d iterations, %d runs, "
              "seed %llu\n",
              sc.name.c_str(), p.num_axes, p.positions_per_axis, p.swarm_size, p.iterations,
              p.runs, static_cast<unsigned long long>(p.seed));
  double wall_sum = 0, cpu_sum = 0;
  for (const int r : config.options.robots) {
    const int a = 1 - r;
    const Transform X_BaBp = a == 0 ? k.X_B1B2 : Transform(k.X_B1B2.inverse());
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = CpuSeconds();
    const PosePlanResult plan = PlanCalibrationPoses(k.nominal[a], BoardRobotModel(k.nominal[r], k.X_FT),
                                                     X_BaBp, k.X_FC, p);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = CpuSeconds() - c0;
    wall_sum += wall;
    cpu_sum += cpu;
    const RejectionCounts& j = plan.rejections;
    std::printf("  %s: %s, best fitness 1/O1 %.6g (run %d), %d evaluations, rejected: active IK %d, "
                "passive IK %d, C1 %d, C2 %d, C3 %d, C4 %d, C5 %d; %.2f s wall, %.2f s CPU\n",
                sc.robot_names[r].c_str(), ToString(plan.status), plan.best_fitness,
                plan.best_run + 1, plan.evaluations, j.active_ik, j.passive_ik, j.c1_joint_limits,
                j.c2_singularity, j.c3_visibility, j.c4_min_distance, j.c5_max_distance, wall, cpu);
    for (size_t run = 0; run < plan.run_fitness.size(); ++run) {
      std::printf("    run %zu: 1/O1 %.6g, predicted position error %.4f mm (similarity gauge "
                  "%.4f mm)%s\n",
                  run + 1, plan.run_fitness[run], 1e3 * plan.run_predicted_error[run],
                  1e3 * plan.run_predicted_similarity_error[run],
                  static_cast<int>(run) == plan.best_run ? " (returned)" : "");
    }
  }
  std::printf("  total: %.2f s wall, %.2f s CPU\n", wall_sum, cpu_sum);
  return 0;
}

}  // namespace twin
