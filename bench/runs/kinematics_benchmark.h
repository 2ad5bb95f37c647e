// `twinbench benchmark-kinematics`: times the analytic end-point Jacobian against forward-mode
// autodiff of the templated forward kinematics (the justification for keeping the analytic
// one), and the forward kinematics itself, for a model file.
#pragma once

#include <string>

namespace twin {

struct KinematicsBenchmarkOptions {
  std::string model;      ///< model file (.yaml/.urdf)
  int evaluations = 20000;  ///< evaluations per figure
};

/// Prints the figures; returns the exit code.
int RunKinematicsBenchmark(const KinematicsBenchmarkOptions& options);

}  // namespace twin
