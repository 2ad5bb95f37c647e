// The client side's connection to a served cell, shared by every client of the cell protocol
// (remote/grpc_cell, remote/cell_check): the credentials named on the command line turned into
// a gRPC channel and the call metadata, and gRPC statuses as text.
#pragma once

#include <memory>
#include <string>

namespace grpc {
class Channel;
class Status;
}  // namespace grpc

namespace twin::remote {

/// How to reach and authenticate to a served cell (file names; empty: not used).
struct GrpcCellCredentials {
  std::string ca_file;    ///< TLS: CA of the server's certificate; empty: plaintext
  std::string cert_file;  ///< TLS: client certificate (PEM)
  std::string key_file;   ///< TLS: its key (PEM)
  std::string token_file; ///< first line: the bearer token
};

/// A channel to a cell and what every call carries.
struct CellChannel {
  std::shared_ptr<grpc::Channel> channel;
  std::string authorization;  ///< "Bearer <token>", or empty without a token
};

/// The channel to `host_port` with `credentials`: TLS when a CA or a client certificate is
/// given, else plaintext. `own_connection`: a connection of its own, not shared with other
/// channels to the same address (a client that must be able to vanish alone). Throws
/// InputError naming `where` for unreadable files, a certificate without its key, or an empty
/// token. Connects lazily (the first call reaches the server).
CellChannel OpenCellChannel(const std::string& host_port, const GrpcCellCredentials& credentials,
                            const std::string& where, bool own_connection = false);

/// "CODE: message" of a gRPC status (e.g. "FAILED_PRECONDITION: no session").
std::string StatusText(const grpc::Status& status);

}  // namespace twin::remote
