// `twinbench serve-cell`: a scenario's twin served over the cell protocol (remote/cell_server.h),
// so that `twinbench run --cell grpc://HOST:PORT` (or any client of the protocol) drives it as
// it would drive a real cell, and the bench scores against the twin's truth channel.
#pragma once

#include <string>

namespace twin {

struct ServeCellOptions {
  std::string scenario;            ///< scenario file
  std::string listen;              ///< HOST:PORT (port 0: a free one, printed)
  int trial = 0;                   ///< study trial, as `run --trial`
  std::string tls_cert_file, tls_key_file, client_ca_file, token_file;
  double heartbeat_timeout_s = 2.0;
  bool truth = true;               ///< serve the truth channel (false: --no-truth)
  bool realtime = false;           ///< pace the simulation to wall-clock time
};

/// Loads the scenario exactly as `run` does (ApplyTrial included), builds its twin, serves it,
/// prints `serving <scenario name> on HOST:PORT` and serves until SIGINT or SIGTERM; returns 0
/// then. Throws InputError for a bad scenario or bad serving options.
int RunServeCell(const ServeCellOptions& options);

}  // namespace twin
