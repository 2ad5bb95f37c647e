// Synthetic optical-axis measurements for benchmarks: a measurements.csv in the format `twinbench
// run` writes, for a robot whose true geometry is the given model perturbed (1 mm, 0.1 deg per
// parameter), servoed perfectly onto 5 camera axes (the camera point and axis fan of the
// synthetic tests, for arms of about 1 m reach), with 0.001 deg of joint noise and exact depths.
// Used by scripts/benchmark_identify.sh to time `twinbench identify` on thousands of rows.
#pragma once

#include <cstdint>
#include <string>

#include "bench/io/model_loader.h"

namespace twin {

/// Options of SynthesizeMeasurements.
struct SynthesizeOptions {
  std::string model;        ///< nominal model file (.yaml/.urdf)
  ModelLinks links;  ///< --base-link / --tip-link of a URDF model
  int rows = 5000;          ///< measurement rows (spread evenly over the 5 axes)
  std::uint64_t seed = 1;   ///< seed of the true geometry and the noise
  std::string out;          ///< output CSV path
};

/// Writes the CSV (atomically); returns the exit code. Throws InputError for bad options or an
/// unreachable axis point.
int RunSynthesizeMeasurements(const SynthesizeOptions& options);

}  // namespace twin
