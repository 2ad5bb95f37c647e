// A Cell served over the cell protocol (proto/twinbench/cell/v1/cell.proto): any Cell
// implementation (the twin, in `twinbench serve-cell`) behind a gRPC server, with the
// protocol's sessions, heartbeat, stop, credentials and refusals enforced here, once, for
// every cell. Optionally it also serves the bench's truth channel (truth.proto) of a twin.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "calib/cell/cell.h"
#include "sim/cell/twin_cell.h"

namespace twin::remote {

/// What Describe answers: the cell as the protocol presents it.
struct CellDescription {
  std::string cell_name;                      ///< e.g. the scenario's name
  std::vector<std::string> robot_names;       ///< one per robot, in index order
  std::vector<std::vector<JointLimits>> limits;  ///< per robot, per joint [rad]
  bool has_camera = false;
  int image_width_px = 0, image_height_px = 0;
  bool has_tracker = false;
  bool has_handclasp = false;
  bool has_clock = false;
};

struct ServerOptions {
  std::string listen;              ///< host:port; port 0 picks a free port (BoundPort())
  std::string tls_cert_file;       ///< server certificate (PEM); empty: plaintext
  std::string tls_key_file;        ///< its key (PEM)
  std::string client_ca_file;      ///< require client certificates signed by this CA (PEM)
  std::string token_file;          ///< require `authorization: Bearer <token>` (first line)
  double heartbeat_timeout_s = 2.0;  ///< silence after which a session ends and motion stops
  /// Stops motion in progress, from any thread (the watchdog's): the cell's MoveTo then
  /// returns early. Null: the cell cannot be stopped mid-move (a move runs to its end).
  std::function<void()> stop_motion;
  /// The twin's truth for the bench's truth channel; null: not offered (UNIMPLEMENTED).
  std::function<TwinTruth()> truth;
  /// The twin's simulated operator for the bench channel's SetOperatorError: the alignment
  /// error's standard deviation [m] (TwinCell::SetOperatorAlignmentError); null: not offered
  /// (UNIMPLEMENTED; a real cell's operator is a person).
  std::function<void(double)> set_operator_error;
};

/// Serves `cell` until Shutdown() or destruction. Every call on `cell` runs on one thread of
/// the server's own, one at a time (the twin's renderer is bound to the thread that made it).
/// Throws InputError naming the option for bad options: an address beyond loopback without
/// TLS and client authentication (client CA or token), unreadable certificate files, a port
/// that cannot be bound.
class CellServer {
 public:
  CellServer(Cell& cell, CellDescription description, ServerOptions options);
  ~CellServer();
  CellServer(const CellServer&) = delete;
  CellServer& operator=(const CellServer&) = delete;

  int BoundPort() const;           ///< the port it listens on
  void Wait();                     ///< blocks until Shutdown()
  void Shutdown();

  struct Impl;  ///< public only so that the .cc's service classes can name it

 private:
  std::unique_ptr<Impl> impl_;
};

/// The bearer token of a token file's text (`--token-file`, `--cell-token-file`): its first
/// line without surrounding blanks; empty when there is none.
std::string TokenOfText(const std::string& text);

/// True for addresses that stay on this machine: 127.0.0.0/8, [::1], localhost (any port).
bool IsLoopbackAddress(const std::string& host_port);

}  // namespace twin::remote
