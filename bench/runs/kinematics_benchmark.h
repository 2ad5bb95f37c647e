// `twinbench benchmark-kinematics`: times the analytic end-point Jacobian against forward-mode
// autodiff of the templated forward kinematics (the justification for keeping the analytic
// one), the forward kinematics itself, and the inverse kinematics, iterative against the
// closed form of a spherical-wrist arm (issue 42), for a model file.
#pragma once

#include <string>

#include "bench/io/model_loader.h"

namespace twin {

struct KinematicsBenchmarkOptions {
  std::string model;      ///< model file (.yaml/.urdf)
  ModelLinks links;  ///< --base-link / --tip-link of a URDF model
  int evaluations = 20000;  ///< evaluations per figure
};

/// Prints the figures; returns the exit code.
int RunKinematicsBenchmark(const KinematicsBenchmarkOptions& options);

}  // namespace twin
