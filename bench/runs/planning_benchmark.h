// `twinbench benchmark-planning SCENARIO`: the pose planning of a scenario's calibration alone
// (calib/planning/pose_planner.h, from what the estimator is told), timed: wall and CPU time
// per robot, evaluations, rejections and the best fitness, so that the planner's speed and its
// result can be compared across code versions without the twin.
#pragma once

#include <string>

namespace twin {

/// Options of RunPlanningBenchmark.
struct PlanningBenchmarkOptions {
  std::string scenario;  ///< scenario with a calibration: section
  int threads = 0;       ///< planner threads (0: the planner's default, one per core)
};

/// Plans every robot of the scenario's calibration and prints the figures; returns the exit
/// code. Throws InputError for bad input.
int RunPlanningBenchmark(const PlanningBenchmarkOptions& options);

}  // namespace twin
