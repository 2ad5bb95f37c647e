// remote/cell_server.h in this process, over the twin of twin_demo.yaml (two robots, the hand
// camera): sessions, the heartbeat watchdog, and 1,000 generated malformed or out-of-range
// requests, each refused, after which the server still answers.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <random>
#include <thread>

#include "bench/io/scenario.h"
#include "calib/common/errors.h"
#include "remote/cell_server.h"
#include "remote/grpc_cell.h"
#include "serve_cell_process.h"

namespace twin::testing {
namespace {

using remote::CellDescription;
using remote::CellServer;
using remote::ServerOptions;

// The demo twin (built once: a few seconds) and its description.
struct DemoTwin {
  Scenario sc = LoadScenario(std::string(TWIN_SOURCE_DIR) + "/scenarios/twin_demo.yaml");
  std::unique_ptr<TwinCell> twin;
  CellDescription desc;
  DemoTwin() {
    desc.cell_name = sc.name;
    for (int k = 0; k < sc.twin.num_robots; ++k) {
      desc.robot_names.push_back(sc.robot_names[k]);
      std::vector<JointLimits> limits;
      for (int i = 0; i < sc.twin.robots[k].model.num_joints(); ++i) {
        limits.push_back(sc.twin.robots[k].model.links[i].limits);
      }
      desc.limits.push_back(limits);
    }
    desc.has_camera = true;
    desc.image_width_px = sc.twin.camera.intrinsics.width;
    desc.image_height_px = sc.twin.camera.intrinsics.height;
    desc.has_clock = true;
  }
};

// The twin is built on the test's thread but never renders here; the server's worker makes
// every call (the renderer, made at the first image, belongs to the worker).
DemoTwin& Demo() {
  static DemoTwin* demo = [] {
    auto* d = new DemoTwin;
    d->twin = std::make_unique<TwinCell>(d->sc.twin, d->sc.path);
    return d;
  }();
  return *demo;
}

ServerOptions Loopback(double heartbeat_s = 5.0) {
  ServerOptions o;
  o.listen = "127.0.0.1:0";
  o.heartbeat_timeout_s = heartbeat_s;
  o.stop_motion = [] { Demo().twin->RequestStop(); };
  return o;
}

std::string OpenSession(pb::Cell::Stub& stub, grpc::StatusCode* code = nullptr) {
  pb::OpenSessionRequest req;
  req.set_client("test");
  pb::OpenSessionResponse resp;
  const grpc::Status s = stub.OpenSession(Context().get(), req, &resp);
  if (code) *code = s.error_code();
  return resp.session_id();
}

TEST(CellServer, LoopbackAddresses) {
  EXPECT_TRUE(remote::IsLoopbackAddress("127.0.0.1:0"));
  EXPECT_TRUE(remote::IsLoopbackAddress("127.3.2.1:50051"));
  EXPECT_TRUE(remote::IsLoopbackAddress("localhost:1"));
  EXPECT_TRUE(remote::IsLoopbackAddress("[::1]:5"));
  EXPECT_FALSE(remote::IsLoopbackAddress("0.0.0.0:0"));
  EXPECT_FALSE(remote::IsLoopbackAddress("[::]:0"));
  EXPECT_FALSE(remote::IsLoopbackAddress("10.0.0.1:80"));
  EXPECT_FALSE(remote::IsLoopbackAddress("128.0.0.1:80"));
  EXPECT_FALSE(remote::IsLoopbackAddress("example.com:80"));
}

TEST(CellServer, BeyondLoopbackNeedsTlsAndClientAuthentication) {
  ServerOptions o = Loopback();
  o.listen = "0.0.0.0:0";
  EXPECT_THROW(CellServer(*Demo().twin, Demo().desc, o), InputError);
  o.token_file = "/nonexistent";  // a token without TLS is not enough
  EXPECT_THROW(CellServer(*Demo().twin, Demo().desc, o), InputError);
}

TEST(CellServer, OneSessionAtATimeAndSilentSessionsEnd) {
  ServerOptions o = Loopback(0.5);
  std::atomic<int> stops{0};  // counted on the server's watchdog thread
  o.stop_motion = [&] { ++stops; };
  CellServer server(*Demo().twin, Demo().desc, o);
  auto stub = RawStub("127.0.0.1:" + std::to_string(server.BoundPort()), "");
  grpc::StatusCode code;
  const std::string first = OpenSession(*stub, &code);
  ASSERT_EQ(code, grpc::OK);
  // Held: a second session is refused, naming the first.
  pb::OpenSessionRequest req;
  pb::OpenSessionResponse resp;
  const grpc::Status refused = stub->OpenSession(Context().get(), req, &resp);
  EXPECT_EQ(refused.error_code(), grpc::FAILED_PRECONDITION);
  // It names the holder by the first 8 digits of its id, never the whole id (a capability).
  EXPECT_EQ(first.size(), 32u);
  EXPECT_NE(refused.error_message().find(first.substr(0, 8)), std::string::npos)
      << refused.error_message();
  EXPECT_EQ(refused.error_message().find(first), std::string::npos) << refused.error_message();
  // Heartbeats every 0.1 s keep it (1 s of them, 2 heartbeat timeouts); 1.2 s of silence ends
  // it (the watchdog looks every 0.05 s).
  for (int i = 0; i < 10; ++i) {
    pb::HeartbeatRequest hb;
    hb.set_session_id(first);
    pb::HeartbeatResponse hr;
    ASSERT_TRUE(stub->Heartbeat(Context().get(), hb, &hr).ok()) << i;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(stops, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  pb::ReadEncodersRequest enc;
  enc.set_session_id(first);
  pb::ReadEncodersResponse q;
  EXPECT_EQ(stub->ReadEncoders(Context().get(), enc, &q).error_code(),
            grpc::FAILED_PRECONDITION);
  EXPECT_GE(stops, 1);
  // A new session opens; the old id stays refused.
  const std::string second = OpenSession(*stub, &code);
  EXPECT_EQ(code, grpc::OK);
  EXPECT_NE(second, first);
  EXPECT_EQ(stub->ReadEncoders(Context().get(), enc, &q).error_code(),
            grpc::FAILED_PRECONDITION);
  enc.set_session_id(second);
  EXPECT_TRUE(stub->ReadEncoders(Context().get(), enc, &q).ok());
  EXPECT_EQ(q.q_rad_size(), 6);
}

// A server remembers why its last 64 sessions ended, no more: a long-running server does not
// grow with every session. An older id is refused all the same, as unknown.
TEST(CellServer, RemembersOnlyTheLastSessionsItEnded) {
  CellServer server(*Demo().twin, Demo().desc, Loopback());
  auto stub = RawStub("127.0.0.1:" + std::to_string(server.BoundPort()), "");
  std::vector<std::string> ids;
  for (int i = 0; i < 70; ++i) {
    grpc::StatusCode code;
    ids.push_back(OpenSession(*stub, &code));
    ASSERT_EQ(code, grpc::OK) << i;
    pb::CloseSessionRequest close;
    close.set_session_id(ids.back());
    pb::CloseSessionResponse closed;
    ASSERT_TRUE(stub->CloseSession(Context().get(), close, &closed).ok()) << i;
  }
  const auto refusal = [&](const std::string& id) {
    pb::ReadEncodersRequest enc;
    enc.set_session_id(id);
    pb::ReadEncodersResponse q;
    const grpc::Status s = stub->ReadEncoders(Context().get(), enc, &q);
    EXPECT_EQ(s.error_code(), grpc::FAILED_PRECONDITION) << id;
    return s.error_message();
  };
  EXPECT_NE(refusal(ids.back()).find("has ended"), std::string::npos);
  EXPECT_NE(refusal(ids[70 - 64]).find("has ended"), std::string::npos);
  EXPECT_NE(refusal(ids[70 - 65]).find("is not the session that holds the cell"),
            std::string::npos);
  EXPECT_NE(refusal(ids.front()).find("is not the session that holds the cell"),
            std::string::npos);
}

// Stop during a move (the twin paced to wall time): the move answers MOVE_STATUS_STOPPED short
// of its target, and the session stays open.
TEST(CellServer, StopEndsTheMoveInProgress) {
  DemoTwin& demo = Demo();
  demo.twin->SetRealtime(true);
  CellServer server(*demo.twin, demo.desc, Loopback());
  auto stub = RawStub("127.0.0.1:" + std::to_string(server.BoundPort()), "");
  const std::string session = OpenSession(*stub);
  pb::ReadEncodersRequest enc;
  enc.set_session_id(session);
  pb::ReadEncodersResponse start;
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc, &start).ok());
  pb::MoveToRequest move;
  move.set_session_id(session);
  for (double q : start.q_rad()) move.add_q_target_rad(q);
  move.set_q_target_rad(0, start.q_rad(0) + 1.0);  // 1 s at 1 rad/s
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    pb::StopRequest stop;
    stop.set_session_id(session);
    pb::StopResponse r;
    EXPECT_TRUE(stub->Stop(Context().get(), stop, &r).ok());
  });
  pb::MoveResult result;
  const grpc::Status status = stub->MoveTo(Context(30).get(), move, &result);
  stopper.join();
  demo.twin->SetRealtime(false);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(result.status(), pb::MOVE_STATUS_STOPPED) << result.reason();
  pb::ReadEncodersResponse after;
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc, &after).ok());  // still the session
  if (result.reason() == "stopped before the motion started") {
    // On a loaded machine the Stop can overtake the move while it waits for its turn: then
    // nothing moved (the protocol's rule for a move waiting when Stop comes).
    EXPECT_EQ(after.q_rad(0), start.q_rad(0));
  } else {
    // Stopped at about 0.3 s of a 1 s move: it moved, and not to the end (wide bounds for a
    // loaded machine).
    EXPECT_GT(after.q_rad(0) - start.q_rad(0), 0.05);
    EXPECT_LT(after.q_rad(0) - start.q_rad(0), 0.9);
  }
  // Back where it started, for the other tests of this process.
  move.set_q_target_rad(0, start.q_rad(0));
  ASSERT_TRUE(stub->MoveTo(Context(30).get(), move, &result).ok());
  EXPECT_EQ(result.status(), pb::MOVE_STATUS_SETTLED) << result.reason();
}

// The client of remote/grpc_cell.h against the in-process server: the same answers as the twin.
TEST(CellServer, GrpcCellSeesWhatTheTwinAnswers) {
  CellServer server(*Demo().twin, Demo().desc, Loopback());
  const std::string address = "127.0.0.1:" + std::to_string(server.BoundPort());
  remote::GrpcCell cell(address, {}, "--cell grpc://" + address);
  EXPECT_EQ(cell.cell_name(), "twin_demo");
  const JointVector q = cell.ReadEncoders(0);
  ASSERT_EQ(q.size(), 6);
  EXPECT_EQ(cell.CameraRobot(), 0);
  EXPECT_TRUE(std::isfinite(cell.ClockSeconds()));
  EXPECT_TRUE(std::isnan(cell.ReadTemperatureC(0)));  // no sensor in twin_demo
  // A region: exactly the region's pixels come back.
  const cv::Mat region = cell.GrabImageRegion(cv::Rect(10, 20, 64, 48));
  EXPECT_EQ(region.cols, 64);
  EXPECT_EQ(region.rows, 48);
  EXPECT_EQ(region.type(), CV_8UC3);
  // A second client is refused while this one holds the cell: an InputError naming --cell.
  try {
    remote::GrpcCell other(address, {}, "--cell grpc://" + address);
    ADD_FAILURE() << "a second session opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--cell grpc://"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("FAILED_PRECONDITION"), std::string::npos) << e.what();
  }
  // No truth offered by this server, nor a simulated operator.
  EXPECT_THROW(cell.Truth(), InputError);
  EXPECT_FALSE(cell.SetOperatorAlignmentError(0.0005));
}

// The bench channel's SetOperatorError reaches the served twin's operator with the value sent,
// bit for bit; a value outside 0 to 10 mm, or not finite, is refused with a status and sets
// nothing.
TEST(CellServer, SimulatedOperatorIsSetOverTheBenchChannel) {
  ServerOptions o = Loopback();
  std::vector<double> set;
  o.set_operator_error = [&set](double sigma_m) { set.push_back(sigma_m); };
  CellServer server(*Demo().twin, Demo().desc, o);
  const std::string address = "127.0.0.1:" + std::to_string(server.BoundPort());
  remote::GrpcCell cell(address, {}, "--cell grpc://" + address);
  EXPECT_TRUE(cell.SetOperatorAlignmentError(0.0005));
  EXPECT_TRUE(cell.SetOperatorAlignmentError(0.0));
  for (const double bad : {0.02, -1e-6, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity()}) {
    try {
      cell.SetOperatorAlignmentError(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("INVALID_ARGUMENT"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(set, (std::vector<double>{0.0005, 0.0}));
}

// 1,000 requests drawn from a seeded generator, every one malformed or out of range: each is
// answered with a non-OK status, or (a well-formed move out of the limits) a refusing
// MoveResult; nothing moves, and the server still answers Describe and a valid call afterwards.
TEST(CellServer, ThousandMalformedRequestsAreRefused) {
  DemoTwin& demo = Demo();
  CellServer server(*demo.twin, demo.desc, Loopback(30.0));
  auto stub = RawStub("127.0.0.1:" + std::to_string(server.BoundPort()), "");
  const std::string session = OpenSession(*stub);
  ASSERT_FALSE(session.empty());
  pb::ReadEncodersRequest enc0;
  enc0.set_session_id(session);
  pb::ReadEncodersResponse before;
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc0, &before).ok());
  const double truth_time_before = demo.twin->Truth().time_s;

  std::mt19937 rng(40);
  const auto pick = [&](int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::uint32_t> bad_robots = {2, 3, 7, 255, 65536, 0x7fffffffu, 0xffffffffu};
  const auto bad_robot = [&] { return bad_robots[pick(bad_robots.size())]; };
  const auto wrong_session = [&]() -> std::string {
    switch (pick(4)) {
      case 0: return "";
      case 1: return session.substr(0, session.size() - 1);
      case 2: return session + "0";
      default: return std::string(1 + pick(300), static_cast<char>('a' + pick(26)));
    }
  };
  const auto targets = [&](int robot, int n) {
    pb::MoveToRequest req;
    req.set_session_id(session);
    req.set_robot(robot);
    const auto& lim = demo.desc.limits[robot];
    for (int i = 0; i < n; ++i) {
      const JointLimits l = lim[i % lim.size()];
      req.add_q_target_rad(0.5 * (l.lower + l.upper));
    }
    return req;
  };
  int counts[10] = {};
  for (int i = 0; i < 1000; ++i) {
    const int kind = pick(10);
    ++counts[kind];
    grpc::Status status;
    pb::MoveResult move;
    bool move_answer = false;
    switch (kind) {
      case 0: {  // a robot index the cell does not have
        pb::MoveToRequest req = targets(0, 6);
        req.set_robot(bad_robot());
        status = stub->MoveTo(Context().get(), req, &move);
        break;
      }
      case 1: {  // a wrong number of joint targets
        int n = pick(40);
        if (n == 6) n = 7;
        pb::MoveToRequest req = targets(pick(2), n);
        status = stub->MoveTo(Context().get(), req, &move);
        break;
      }
      case 2: {  // NaN or an infinity
        pb::MoveToRequest req = targets(pick(2), 6);
        const double bad[] = {nan, inf, -inf, -nan};
        req.set_q_target_rad(pick(6), bad[pick(4)]);
        status = stub->MoveTo(Context().get(), req, &move);
        break;
      }
      case 3: {  // finite, well formed, beyond a joint limit: the cell refuses, nothing moves
        const int robot = pick(2);
        pb::MoveToRequest req = targets(robot, 6);
        const int j = pick(6);
        const JointLimits l = demo.desc.limits[robot][j];
        const double beyond[] = {l.upper + 0.01, l.lower - 0.01, 1e300, -1e300, l.upper + 100};
        req.set_q_target_rad(j, beyond[pick(5)]);
        status = stub->MoveTo(Context().get(), req, &move);
        move_answer = true;
        break;
      }
      case 4: {  // an empty or negative region, or numbers beyond any camera
        pb::GrabImageRequest req;
        req.set_session_id(session);
        pb::PixelRegion* r = req.mutable_region();
        r->set_x_px(pick(2000) - 1000);
        r->set_y_px(pick(2000) - 1000);
        switch (pick(4)) {
          case 0: r->set_width_px(0); r->set_height_px(pick(100)); break;
          case 1: r->set_width_px(-pick(1000) - 1); r->set_height_px(10); break;
          case 2: r->set_width_px(10); r->set_height_px(-pick(1000)); break;
          default:
            r->set_x_px(2147483647 - pick(100));
            r->set_width_px(2147483647);
            r->set_height_px(2147483647);
        }
        pb::GrabImageResponse resp;
        status = stub->GrabImage(Context().get(), req, &resp);
        break;
      }
      case 5: {  // an unknown or unspecified bracket target
        pb::MountTargetRequest req;
        req.set_session_id(session);
        const int values[] = {0, 3, 4, 99, -1, -100000, 2147483647};
        req.set_target(static_cast<pb::BracketTarget>(values[pick(7)]));
        status = stub->MountTarget(Context().get(), req, &move);
        break;
      }
      case 6: {  // a wrong or missing session id on a valid request
        pb::MoveToRequest req = targets(0, 6);
        req.set_session_id(wrong_session());
        status = stub->MoveTo(Context().get(), req, &move);
        break;
      }
      case 7: {  // wrong session on the other methods
        const std::string id = wrong_session();
        switch (pick(5)) {
          case 0: {
            pb::ReadEncodersRequest r; r.set_session_id(id); pb::ReadEncodersResponse a;
            status = stub->ReadEncoders(Context().get(), r, &a); break;
          }
          case 1: {
            pb::GrabImageRequest r; r.set_session_id(id); pb::GrabImageResponse a;
            status = stub->GrabImage(Context().get(), r, &a); break;
          }
          case 2: {
            pb::ExchangeToolsRequest r; r.set_session_id(id);
            status = stub->ExchangeTools(Context().get(), r, &move); break;
          }
          case 3: {
            pb::HeartbeatRequest r; r.set_session_id(id); pb::HeartbeatResponse a;
            status = stub->Heartbeat(Context().get(), r, &a); break;
          }
          default: {
            pb::CloseSessionRequest r; r.set_session_id(id); pb::CloseSessionResponse a;
            status = stub->CloseSession(Context().get(), r, &a); break;
          }
        }
        break;
      }
      case 8: {  // bad robot indices on the per-robot reads and the handclasp
        const std::uint32_t robot = bad_robot();
        switch (pick(4)) {
          case 0: {
            pb::ReadEncodersRequest r; r.set_session_id(session); r.set_robot(robot);
            pb::ReadEncodersResponse a; status = stub->ReadEncoders(Context().get(), r, &a); break;
          }
          case 1: {
            pb::MeasureTrackerRequest r; r.set_session_id(session); r.set_robot(robot);
            pb::MeasureTrackerResponse a;
            status = stub->MeasureTracker(Context().get(), r, &a); break;
          }
          case 2: {
            pb::ReadTemperatureRequest r; r.set_session_id(session); r.set_robot(robot);
            pb::ReadTemperatureResponse a;
            status = stub->ReadTemperature(Context().get(), r, &a); break;
          }
          default: {
            pb::JogTipToContactRequest r; r.set_session_id(session); r.set_jogged_robot(robot);
            status = stub->JogTipToContact(Context().get(), r, &move); break;
          }
        }
        break;
      }
      default: {  // a move with NaN and a wrong length and a bad robot at once
        pb::MoveToRequest req;
        req.set_session_id(pick(2) ? session : wrong_session());
        req.set_robot(pick(2) ? bad_robot() : 1);
        for (int k = 0, n = 1 + pick(20); k < n; ++k) req.add_q_target_rad(pick(2) ? nan : 1e308);
        if (req.q_target_rad_size() == 6) req.set_q_target_rad(0, nan);
        status = stub->MoveTo(Context().get(), req, &move);
      }
    }
    if (move_answer && status.ok()) {
      EXPECT_TRUE(move.status() == pb::MOVE_STATUS_OUT_OF_LIMITS ||
                  move.status() == pb::MOVE_STATUS_INVALID_INPUT)
          << "request " << i << " (kind " << kind << "): move status " << move.status();
    } else {
      EXPECT_FALSE(status.ok()) << "request " << i << " (kind " << kind << ") was accepted";
      EXPECT_NE(status.error_code(), grpc::INTERNAL)
          << "request " << i << " (kind " << kind << "): " << status.error_message();
      EXPECT_NE(status.error_code(), grpc::UNAVAILABLE)
          << "request " << i << " (kind " << kind << "): " << status.error_message();
    }
  }
  for (int kind = 0; kind < 10; ++kind) EXPECT_GT(counts[kind], 50) << kind;
  // Still serving; nothing moved, no simulated time passed.
  pb::DescribeResponse d;
  EXPECT_TRUE(stub->Describe(Context().get(), pb::DescribeRequest(), &d).ok());
  EXPECT_EQ(d.robots_size(), 2);
  pb::ReadEncodersResponse after;
  ASSERT_TRUE(stub->ReadEncoders(Context().get(), enc0, &after).ok());
  ASSERT_EQ(after.q_rad_size(), before.q_rad_size());
  for (int j = 0; j < after.q_rad_size(); ++j) EXPECT_EQ(after.q_rad(j), before.q_rad(j)) << j;
  EXPECT_EQ(demo.twin->Truth().time_s, truth_time_before);
}

}  // namespace
}  // namespace twin::testing
