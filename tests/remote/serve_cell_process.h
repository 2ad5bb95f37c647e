// Helpers of the remote tests: throwaway certificates (the openssl CLI), a `twinbench serve-cell`
// subprocess whose bound port is read from its first line, and raw protocol stubs.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "twinbench/bench/v1/truth.grpc.pb.h"
#include "twinbench/cell/v1/cell.grpc.pb.h"

namespace twin::testing {

namespace pb = ::twinbench::cell::v1;

/// A fresh folder under the system temp dir, removed at destruction.
class TempDir {
 public:
  TempDir() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "twinbench_remote_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// True when the openssl CLI is on PATH (the certificate tests skip without it).
inline bool HaveOpenssl() {
  return std::system("command -v openssl >/dev/null 2>&1") == 0;
}

/// ca.pem, server.pem/.key (CN and subjectAltName IP:127.0.0.1), client.pem/.key (signed by
/// the CA) and other_ca.pem/other_client.pem/.key (a second, unrelated CA and its client) in
/// `dir`, made with the openssl CLI. False when openssl failed.
inline bool MakeCertificates(const std::string& dir) {
  const std::string q = "cd '" + dir + "' && ";
  const std::string quiet = " >/dev/null 2>&1";
  const auto sh = [&](const std::string& cmd) {
    return std::system((q + cmd + quiet).c_str()) == 0;
  };
  const auto ca = [&](const std::string& name) {
    return sh("openssl req -x509 -newkey rsa:2048 -nodes -keyout " + name + ".key -out " + name +
              ".pem -days 2 -subj /CN=" + name);
  };
  const auto leaf = [&](const std::string& name, const std::string& ca_name,
                        const std::string& cn, const std::string& ext) {
    if (!sh("openssl req -newkey rsa:2048 -nodes -keyout " + name + ".key -out " + name +
            ".csr -subj /CN=" + cn)) {
      return false;
    }
    std::string extfile;
    if (!ext.empty()) {
      std::ofstream(dir + "/" + name + ".ext") << ext << "\n";
      extfile = " -extfile " + name + ".ext";
    }
    return sh("openssl x509 -req -in " + name + ".csr -CA " + ca_name + ".pem -CAkey " + ca_name +
              ".key -CAcreateserial -out " + name + ".pem -days 2" + extfile);
  };
  return ca("ca") && ca("other_ca") &&
         leaf("server", "ca", "127.0.0.1", "subjectAltName=IP:127.0.0.1") &&
         leaf("client", "ca", "client", "") && leaf("other_client", "other_ca", "client", "");
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

/// `twinbench serve-cell ARGS`, running; its stdout and stderr go to a file. port() is 0 when it
/// did not print its `serving ... on HOST:PORT` line in time (output() says why).
class ServeCellProcess {
 public:
  ServeCellProcess(const std::vector<std::string>& args, double start_timeout_s = 60.0) {
    log_ = (std::filesystem::temp_directory_path() /
            ("twinbench_serve_" + std::to_string(getpid()) + "_" +
             std::to_string(reinterpret_cast<std::uintptr_t>(this)) + ".log"))
               .string();
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      dup2(fd, 1);
      dup2(fd, 2);
      std::vector<std::string> argv = {TWINBENCH_BIN, "serve-cell"};
      argv.insert(argv.end(), args.begin(), args.end());
      std::vector<char*> c;
      for (auto& a : argv) c.push_back(a.data());
      c.push_back(nullptr);
      execv(c[0], c.data());
      _exit(127);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::regex line("serving .* on [^ ]*:([0-9]+)");
    while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() <
           start_timeout_s) {
      std::smatch m;
      const std::string text = ReadText(log_);
      if (std::regex_search(text, m, line)) {
        port_ = std::stoi(m[1]);
        return;
      }
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        return;
      }
      usleep(20000);
    }
  }
  ~ServeCellProcess() {
    Stop(SIGTERM, 10.0);
    std::remove(log_.c_str());
  }
  int port() const { return port_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  std::string output() const { return ReadText(log_); }
  /// Waits up to timeout_s for the process to end by itself (or, with `sig`, after sending it);
  /// its exit code, -1 when it did not exit normally in time (it is then killed).
  int Stop(int sig = 0, double timeout_s = 10.0) {
    if (exited_) return code_;
    if (sig != 0) kill(pid_, sig);
    const auto t0 = std::chrono::steady_clock::now();
    for (;;) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        return code_;
      }
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >
          timeout_s) {
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        exited_ = true;
        code_ = -1;
        return code_;
      }
      usleep(20000);
    }
  }
  bool exited() const { return exited_; }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
  bool exited_ = false;
  int code_ = -1;
  std::string log_;
};

/// A raw stub of the cell protocol: TLS with `ca` (and client `cert`/`key` when given), or
/// plaintext for an empty `ca`.
inline std::unique_ptr<pb::Cell::Stub> RawStub(const std::string& address, const std::string& ca,
                                               const std::string& cert = "",
                                               const std::string& key = "") {
  std::shared_ptr<grpc::ChannelCredentials> creds;
  if (ca.empty()) {
    creds = grpc::InsecureChannelCredentials();
  } else {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ReadText(ca);
    if (!cert.empty()) {
      ssl.pem_cert_chain = ReadText(cert);
      ssl.pem_private_key = ReadText(key);
    }
    creds = grpc::SslCredentials(ssl);
  }
  return pb::Cell::NewStub(grpc::CreateChannel(address, creds));
}

/// A client context with a deadline and, when given, the bearer token.
inline std::unique_ptr<grpc::ClientContext> Context(double deadline_s = 10.0,
                                                     const std::string& token = "") {
  auto ctx = std::make_unique<grpc::ClientContext>();
  ctx->set_deadline(std::chrono::system_clock::now() +
                    std::chrono::milliseconds(static_cast<int>(deadline_s * 1000)));
  if (!token.empty()) ctx->AddMetadata("authorization", "Bearer " + token);
  return ctx;
}

}  // namespace twin::testing
