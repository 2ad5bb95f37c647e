// `twinbench cell-check grpc://HOST:PORT`: the conformance battery of the cell protocol
// (proto/twinbench/cell/v1/cell.proto). Any server of the protocol (the twin's `serve-cell`, a
// hardware adapter of adapters/python/) runs it before a procedure drives the cell. Each check
// prints PASS, FAIL or SKIP with what it saw; a FAIL names what the server did wrong.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace twin::remote {

struct CellCheckOptions {
  std::string address;         ///< grpc://HOST:PORT
  std::string tls_ca_file;     ///< TLS: CA of the server's certificate (empty: plaintext)
  std::string tls_cert_file;   ///< client certificate (PEM), where the server requires one
  std::string tls_key_file;
  std::string token_file;      ///< bearer token, where the server requires one
  /// The checks that move a robot (units, refusals, clock, stop on disconnect) run only with
  /// this set: the operator says the cell is clear. Without it they are skipped.
  bool allow_motion = false;
  int robot = 0;               ///< the robot the motion checks move
  /// The stop-on-disconnect check's move of joint 1 [rad]: long enough that it is still
  /// under way when the client disappears.
  double stop_move_rad = 1.0;
};

enum class CheckOutcome { kPass, kFail, kSkip };

struct CheckLine {
  std::string name;            ///< e.g. "units"
  CheckOutcome outcome = CheckOutcome::kSkip;
  std::string detail;          ///< what was seen
};

/// Runs the battery and prints one line a check to `out`. Throws InputError naming the address
/// when the server cannot be reached or refuses the credentials at Describe.
std::vector<CheckLine> RunCellCheck(const CellCheckOptions& options, std::ostream& out);

/// The verb: 0 when no check failed, 1 when one did.
int RunCellCheckVerb(const CellCheckOptions& options);

}  // namespace twin::remote
