#include "remote/cell_channel.h"

#include <fstream>
#include <sstream>

#include <grpcpp/grpcpp.h>

#include "calib/common/errors.h"
#include "remote/cell_server.h"  // IsLoopbackAddress, TokenOfText

namespace twin::remote {

namespace {

std::string ReadFile(const std::string& path, const std::string& where, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where, "cannot read the " + what + " '" + path + "'");
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

const char* CodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::OK: return "OK";
    case grpc::CANCELLED: return "CANCELLED";
    case grpc::UNKNOWN: return "UNKNOWN";
    case grpc::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::NOT_FOUND: return "NOT_FOUND";
    case grpc::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::UNAUTHENTICATED: return "UNAUTHENTICATED";
    case grpc::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::ABORTED: return "ABORTED";
    case grpc::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::INTERNAL: return "INTERNAL";
    case grpc::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::DATA_LOSS: return "DATA_LOSS";
    default: return "status";
  }
}

}  // namespace

CellChannel OpenCellChannel(const std::string& host_port, const GrpcCellCredentials& credentials,
                            const std::string& where, bool own_connection) {
  CellChannel out;
  std::shared_ptr<grpc::ChannelCredentials> channel_credentials;
  const bool channel_credentials_tls = !credentials.ca_file.empty() ||
                                       !credentials.cert_file.empty() ||
                                       !credentials.key_file.empty();
  if (channel_credentials_tls) {
    if (credentials.cert_file.empty() != credentials.key_file.empty()) {
      throw InputError(where, "a client certificate needs both --cell-cert and --cell-key");
    }
    grpc::SslCredentialsOptions ssl;
    if (!credentials.ca_file.empty()) {
      ssl.pem_root_certs = ReadFile(credentials.ca_file, where, "CA certificate (--cell-ca)");
    }
    if (!credentials.cert_file.empty()) {
      ssl.pem_cert_chain =
          ReadFile(credentials.cert_file, where, "client certificate (--cell-cert)");
      ssl.pem_private_key = ReadFile(credentials.key_file, where, "client key (--cell-key)");
    }
    channel_credentials = grpc::SslCredentials(ssl);
  } else {
    channel_credentials = grpc::InsecureChannelCredentials();
  }
  if (!credentials.token_file.empty()) {
    // A bearer token in clear text is for this machine only.
    if (!channel_credentials_tls && !IsLoopbackAddress(host_port)) {
      throw InputError(where, "a token is sent only over TLS beyond loopback: give --cell-ca");
    }
    const std::string token = TokenOfText(
        ReadFile(credentials.token_file, where, "token file (--cell-token-file)"));
    if (token.empty()) throw InputError(where, "the token file holds no token on its first line");
    out.authorization = "Bearer " + token;
  }
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(256 << 20);
  if (own_connection) args.SetInt("grpc.use_local_subchannel_pool", 1);
  out.channel = grpc::CreateCustomChannel(host_port, channel_credentials, args);
  return out;
}

std::string StatusText(const grpc::Status& status) {
  return std::string(CodeName(status.error_code())) + ": " + status.error_message();
}

}  // namespace twin::remote
