// `twinbench serve-cell` as a process: where it may listen, the credentials it requires, a client
// killed in the middle of a move, and its end on SIGINT / SIGTERM.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <thread>

#include "../bench/cli_run.h"
#include "serve_cell_process.h"

namespace twin::testing {
namespace {

const std::string kTracker =
    std::string(TWIN_SOURCE_DIR) + "/scenarios/tracker_single_reinovo.yaml";

grpc::StatusCode DescribeCode(pb::Cell::Stub& stub, const std::string& token = "") {
  pb::DescribeResponse d;
  return stub.Describe(Context(10, token).get(), pb::DescribeRequest(), &d).error_code();
}

TEST(ServeCellCli, BeyondLoopbackWithoutTlsAndAuthenticationExitsTwo) {
  if (!HaveOpenssl()) GTEST_SKIP() << "no openssl CLI to make certificates";
  TempDir dir;
  ASSERT_TRUE(MakeCertificates(dir.path()));
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{},
        // TLS alone authenticates no client.
        std::vector<std::string>{"--tls-cert", dir / "server.pem", "--tls-key",
                                 dir / "server.key"}}) {
    std::vector<std::string> args = {"serve-cell", kTracker, "--listen", "0.0.0.0:0"};
    args.insert(args.end(), extra.begin(), extra.end());
    const ProcessRun r = TwinbenchArgs(args, 60);
    EXPECT_TRUE(r.exited && r.code == 2) << r.output;
    EXPECT_NE(r.output.find("error: --listen"), std::string::npos) << r.output;
  }
}

TEST(ServeCellCli, ClientWithoutCertificateIsRefused) {
  if (!HaveOpenssl()) GTEST_SKIP() << "no openssl CLI to make certificates";
  TempDir dir;
  ASSERT_TRUE(MakeCertificates(dir.path()));
  ServeCellProcess server({kTracker, "--listen", "127.0.0.1:0", "--tls-cert", dir / "server.pem",
                           "--tls-key", dir / "server.key", "--client-ca", dir / "ca.pem"});
  ASSERT_GT(server.port(), 0) << server.output();
  // No client certificate; one signed by another CA; plaintext: all refused.
  EXPECT_NE(DescribeCode(*RawStub(server.address(), dir / "ca.pem")), grpc::OK);
  EXPECT_NE(DescribeCode(*RawStub(server.address(), dir / "ca.pem", dir / "other_client.pem",
                                  dir / "other_client.key")),
            grpc::OK);
  EXPECT_NE(DescribeCode(*RawStub(server.address(), "")), grpc::OK);
  // The right one is served.
  EXPECT_EQ(DescribeCode(*RawStub(server.address(), dir / "ca.pem", dir / "client.pem",
                                  dir / "client.key")),
            grpc::OK);
}

TEST(ServeCellCli, MissingOrWrongTokenIsUnauthenticated) {
  if (!HaveOpenssl()) GTEST_SKIP() << "no openssl CLI to make certificates";
  TempDir dir;
  ASSERT_TRUE(MakeCertificates(dir.path()));
  std::ofstream(dir / "token") << "s3cret-token-40\n";
  std::ofstream(dir / "wrong") << "s3cret-token-41\n";
  ServeCellProcess server({kTracker, "--listen", "127.0.0.1:0", "--tls-cert", dir / "server.pem",
                           "--tls-key", dir / "server.key", "--token-file", dir / "token"});
  ASSERT_GT(server.port(), 0) << server.output();
  auto stub = RawStub(server.address(), dir / "ca.pem");
  EXPECT_EQ(DescribeCode(*stub), grpc::UNAUTHENTICATED);
  EXPECT_EQ(DescribeCode(*stub, "s3cret-token-41"), grpc::UNAUTHENTICATED);
  EXPECT_EQ(DescribeCode(*stub, "s3cret-token-4"), grpc::UNAUTHENTICATED);
  EXPECT_EQ(DescribeCode(*stub, "s3cret-token-400"), grpc::UNAUTHENTICATED);
  pb::OpenSessionResponse opened;
  EXPECT_EQ(stub->OpenSession(Context().get(), pb::OpenSessionRequest(), &opened).error_code(),
            grpc::UNAUTHENTICATED);
  EXPECT_EQ(DescribeCode(*stub, "s3cret-token-40"), grpc::OK);
  // `run --cell` with the wrong token file: exit 2 naming --cell.
  const std::string cell = "grpc://127.0.0.1:" + std::to_string(server.port());
  const ProcessRun r = TwinbenchArgs({"run", kTracker, "--out", dir / "out", "--quiet", "--cell",
                                      cell, "--cell-ca", dir / "ca.pem", "--cell-token-file",
                                      dir / "wrong"},
                                     60);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell " + cell), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("UNAUTHENTICATED"), std::string::npos) << r.output;
}

// The client of the killed-mid-move test, run as a child process of this binary
// (--gtest_also_run_disabled_tests): opens a session on TWINBENCH_TEST_CELL, prints its id and
// the target, and starts a long move of joint 1 (2 rad; 2 s at the default 1 rad/s ramp).
TEST(RemoteHelper, DISABLED_MoveClient) {
  const char* address = std::getenv("TWINBENCH_TEST_CELL");
  ASSERT_NE(address, nullptr);
  auto stub = RawStub(address, "");
  pb::DescribeResponse d;
  ASSERT_TRUE(stub->Describe(Context().get(), pb::DescribeRequest(), &d).ok());
  pb::OpenSessionResponse opened;
  ASSERT_TRUE(stub->OpenSession(Context().get(), pb::OpenSessionRequest(), &opened).ok());
  pb::ReadEncodersRequest enc;
  enc.set_session_id(opened.session_id());
  pb::ReadEncodersResponse q;
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc, &q).ok());
  pb::MoveToRequest move;
  move.set_session_id(opened.session_id());
  for (double v : q.q_rad()) move.add_q_target_rad(v);
  const pb::JointLimit lim = d.robots(0).joints(0);
  const double up = lim.upper_rad() - q.q_rad(0), down = q.q_rad(0) - lim.lower_rad();
  const double target = up > down ? q.q_rad(0) + std::min(2.0, up - 0.05)
                                   : q.q_rad(0) - std::min(2.0, down - 0.05);
  move.set_q_target_rad(0, target);
  std::printf("session %s\nstart %.17g\ntarget %.17g\nmoving\n", opened.session_id().c_str(),
              q.q_rad(0), target);
  std::fflush(stdout);
  // Heartbeats during the move, as the protocol asks of every client (a client that falls
  // silent, even inside a call, loses its session and the motion stops).
  std::atomic<bool> done{false};
  std::thread heartbeat([&] {
    while (!done) {
      pb::HeartbeatRequest hb;
      hb.set_session_id(opened.session_id());
      pb::HeartbeatResponse hr;
      (void)stub->Heartbeat(Context().get(), hb, &hr);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  pb::MoveResult result;
  const grpc::Status status = stub->MoveTo(Context(300).get(), move, &result);
  done = true;
  heartbeat.join();
  std::printf("move ended: %d %s, status %d %s\n", status.error_code(),
              status.error_message().c_str(), result.status(), result.reason().c_str());
}

TEST(ServeCellCli, ClientKilledMidMoveEndsSessionAndStopsMotion) {
  constexpr double kHeartbeatS = 0.5;
  constexpr double kMarginS = 1.5;  // detection, stop and reopening
  ServeCellProcess server({kTracker, "--listen", "127.0.0.1:0", "--realtime",
                           "--heartbeat-timeout", "0.5"});
  ASSERT_GT(server.port(), 0) << server.output();
  TempDir dir;
  const std::string log = dir / "client.log";
  const pid_t child = fork();
  if (child == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    dup2(fd, 1);
    dup2(fd, 2);
    setenv("TWINBENCH_TEST_CELL", server.address().c_str(), 1);
    execl("/proc/self/exe", "remote_tests", "--gtest_filter=RemoteHelper.DISABLED_MoveClient",
          "--gtest_also_run_disabled_tests", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait for the move to start, then let it run 0.6 s (of 2 s) and kill the client.
  std::string session;
  double start = 0, target = 0;
  const auto t0 = std::chrono::steady_clock::now();
  std::smatch m;
  const std::regex re("session ([0-9a-f]+)\nstart (\\S+)\ntarget (\\S+)\nmoving");
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
    const std::string text = ReadText(log);
    if (std::regex_search(text, m, re)) {
      session = m[1];
      start = std::stod(m[2]);
      target = std::stod(m[3]);
      break;
    }
    usleep(10000);
  }
  ASSERT_FALSE(session.empty()) << ReadText(log) << server.output();
  ASSERT_GT(std::abs(target - start), 1.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  const auto killed = std::chrono::steady_clock::now();
  EXPECT_EQ(ReadText(log).find("move ended"), std::string::npos) << ReadText(log);

  // A new session opens within the heartbeat timeout plus the margin.
  auto stub = RawStub(server.address(), "");
  std::string fresh;
  double waited = 0;
  while (waited < kHeartbeatS + kMarginS + 1.0) {
    pb::OpenSessionResponse opened;
    if (stub->OpenSession(Context().get(), pb::OpenSessionRequest(), &opened).ok()) {
      fresh = opened.session_id();
      break;
    }
    usleep(20000);
    waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  }
  waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  ASSERT_FALSE(fresh.empty()) << server.output();
  EXPECT_LE(waited, kHeartbeatS + kMarginS);
  std::printf("a new session opened %.3f s after the client was killed\n", waited);
  // The robot stands: two encoder reads 0.3 s apart agree (to 1e-4 rad, 11 sigma of the
  // scenario's 0.0005 deg encoder noise), between the start and the target, short of the
  // target by more than 0.3 rad.
  pb::ReadEncodersRequest enc;
  enc.set_session_id(fresh);
  pb::ReadEncodersResponse a, b;
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc, &a).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc, &b).ok());
  ASSERT_EQ(a.q_rad_size(), b.q_rad_size());
  for (int j = 0; j < a.q_rad_size(); ++j) EXPECT_NEAR(a.q_rad(j), b.q_rad(j), 1e-4) << j;
  EXPECT_GT(std::abs(target - a.q_rad(0)), 0.3) << "reached the target: not stopped";
  EXPECT_GT(std::abs(a.q_rad(0) - start), 0.05) << "never moved";
  // The old session is refused.
  enc.set_session_id(session);
  const grpc::Status old = stub->ReadEncoders(Context().get(), enc, &a);
  EXPECT_EQ(old.error_code(), grpc::FAILED_PRECONDITION) << old.error_message();
  // SIGINT ends the server cleanly.
  EXPECT_EQ(server.Stop(SIGINT), 0) << server.output();
}

}  // namespace
}  // namespace twin::testing
