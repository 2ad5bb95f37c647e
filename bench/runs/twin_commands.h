// CLI verbs that run the MuJoCo twin: `render` (pictures of the cell) and `benchmark-twin`.
#pragma once

#include <string>

namespace twin {

/// Options of RunRender.
struct RenderOptions {
  std::string scenario;  ///< scenario file
  std::string out_dir;   ///< output folder (created; files appear only when all are written)
  int poses = 4;         ///< poses to show: the initial one plus small wrist moves of the board
  int overview_width = 1280;   ///< [px]
  int overview_height = 960;   ///< [px]
};

/// Writes hand-camera and third-person PNGs of the scenario's cell at a few poses (a one-robot
/// cell, without a camera: the third-person ones only); returns the process exit code. Throws
/// InputError for bad input.
int RunRender(const RenderOptions& options);

/// Options of RunTwinBenchmark.
struct TwinBenchmarkOptions {
  std::string scenario;  ///< scenario file
  int frames = 200;      ///< frames per measurement
  int moves = 40;        ///< settled moves to time
};

/// Prints ms per frame of GrabImage vs a bare mjr_render + mjr_readPixels loop, ms per
/// settled move, and frames per second with one and with two worker processes. Throws
/// InputError for a cell without a hand camera (one robot).
int RunTwinBenchmark(const TwinBenchmarkOptions& options);

}  // namespace twin
