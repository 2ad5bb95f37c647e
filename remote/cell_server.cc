// The cell protocol's server (remote/cell_server.h): one worker thread owns every call on the
// Cell, handlers post tasks to it and wait; a watchdog ends silent sessions.
#include "remote/cell_server.h"

#include <arpa/inet.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <future>
#include <iomanip>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "calib/common/errors.h"
#include "remote/proto_convert.h"
#include "twinbench/bench/v1/truth.grpc.pb.h"
#include "twinbench/cell/v1/cell.grpc.pb.h"

namespace twin::remote {

namespace {

using grpc::ServerContext;
using grpc::Status;
using grpc::StatusCode;
using Clock = std::chrono::steady_clock;

// Bounds of a pixel region's numbers (a sanity bound far beyond any camera; it keeps the
// arithmetic of clipping free of overflow).
constexpr int kMaxRegionCoordinate = 1 << 20;
// The simulated operator's largest alignment error [m]: the handclasp section's own limit (a
// 10 mm miss is no contact; bench/runs/handclasp_run.cc).
constexpr double kMaxOperatorSigmaM = 0.01;

std::string ReadFileOrThrow(const std::string& path, const std::string& option) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(option, "cannot read '" + path + "'");
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// The token of a token file.
std::string ReadToken(const std::string& path, const std::string& option) {
  const std::string token = TokenOfText(ReadFileOrThrow(path, option));
  if (token.empty()) throw InputError(option, "'" + path + "' holds no token on its first line");
  return token;
}

// Equal strings, in a time that does not depend on where they differ.
bool ConstantTimeEqual(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned char>(x ^ y);
  }
  return diff == 0;
}

std::string NewSessionId() {
  std::random_device rd;
  std::ostringstream os;
  os << std::hex << std::setfill('0');
  for (int i = 0; i < 4; ++i) os << std::setw(8) << (rd() & 0xffffffffu);
  return os.str();
}

Status Invalid(const std::string& what) { return Status(StatusCode::INVALID_ARGUMENT, what); }

}  // namespace

bool IsLoopbackAddress(const std::string& host_port) {
  std::string host;
  if (!host_port.empty() && host_port[0] == '[') {
    const auto close = host_port.find(']');
    if (close == std::string::npos) return false;
    host = host_port.substr(1, close - 1);
  } else {
    const auto colon = host_port.rfind(':');
    host = colon == std::string::npos ? host_port : host_port.substr(0, colon);
  }
  if (host == "localhost") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) {
    return (ntohl(v4.s_addr) >> 24) == 127;
  }
  in6_addr v6{};
  if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) return IN6_IS_ADDR_LOOPBACK(&v6);
  return false;
}

struct CellServer::Impl {
  Cell& cell;
  CellDescription desc;
  ServerOptions opt;
  std::string token;  // empty: no token required

  // Sessions.
  std::mutex session_mutex;
  std::string live_id, live_client;
  Clock::time_point last_seen;
  std::map<std::string, std::string> ended;  // id -> why it ended, the last kEndedKept
  std::deque<std::string> ended_order;       // their ids, oldest first
  // Ended sessions remembered, to tell their client why (an older one is just unknown): a
  // server up for months must not grow with every session it served.
  static constexpr std::size_t kEndedKept = 64;

  // Remembers why session `id` ended; the caller holds session_mutex.
  void NoteEnded(const std::string& id, const std::string& why) {
    if (ended.emplace(id, why).second) ended_order.push_back(id);
    if (ended_order.size() > kEndedKept) {
      ended.erase(ended_order.front());
      ended_order.pop_front();
    }
  }

  // The worker: every call on the cell, one at a time.
  std::mutex queue_mutex;
  std::condition_variable queue_cv;
  std::deque<std::function<void()>> queue;
  bool stopping = false;
  std::string running_session;  // the session of the task the worker runs now ("" none)
  std::thread worker, watchdog;
  std::mutex watchdog_mutex;
  std::condition_variable watchdog_cv;

  std::atomic<std::uint64_t> stops{0};  // stop requests made so far (Stop, watchdog, cancel)
  std::atomic<std::uint64_t> stop_calls{0};  // Stop calls of the protocol so far

  std::unique_ptr<grpc::Service> cell_service, truth_service;
  std::unique_ptr<grpc::Server> server;
  int port = 0;
  std::once_flag shutdown_once;

  Impl(Cell& c, CellDescription d, ServerOptions o)
      : cell(c), desc(std::move(d)), opt(std::move(o)) {}

  // --- credentials -------------------------------------------------------------------------

  Status Authorize(ServerContext* ctx) const {
    if (token.empty()) return Status::OK;
    const auto& md = ctx->client_metadata();
    const auto it = md.find("authorization");
    if (it == md.end()) {
      return Status(StatusCode::UNAUTHENTICATED, "this cell requires a bearer token");
    }
    const std::string given(it->second.data(), it->second.size());
    if (!ConstantTimeEqual(given, "Bearer " + token)) {
      return Status(StatusCode::UNAUTHENTICATED, "wrong bearer token");
    }
    return Status::OK;
  }

  // --- sessions ----------------------------------------------------------------------------

  // OK and the session's clock restarted when `id` is the live session.
  Status Touch(const std::string& id) {
    std::lock_guard<std::mutex> lock(session_mutex);
    if (!live_id.empty() && ConstantTimeEqual(id, live_id)) {  // the id is a capability
      last_seen = Clock::now();
      return Status::OK;
    }
    if (id.empty()) {
      return Status(StatusCode::FAILED_PRECONDITION,
                    "no session id given (open a session with OpenSession first)");
    }
    const auto it = ended.find(id);
    if (it != ended.end()) {
      return Status(StatusCode::FAILED_PRECONDITION, "session " + id + " has ended: " + it->second);
    }
    return Status(StatusCode::FAILED_PRECONDITION,
                  "session '" + id.substr(0, 64) + "' is not the session that holds the cell");
  }

  bool IsLive(const std::string& id) {
    std::lock_guard<std::mutex> lock(session_mutex);
    return !live_id.empty() && ConstantTimeEqual(id, live_id);
  }

  // Ends session `id` (if it is the live one) for `why`, and stops motion.
  void EndSession(const std::string& id, const std::string& why, bool stop) {
    {
      std::lock_guard<std::mutex> lock(session_mutex);
      if (live_id.empty() || id != live_id) return;
      NoteEnded(live_id, why);
      live_id.clear();
      live_client.clear();
    }
    if (stop) StopMotion();
  }

  void StopMotion() {
    ++stops;
    if (opt.stop_motion) opt.stop_motion();
  }

  // `result` of a motion call as the protocol has it: a move that did not settle because a stop
  // was requested while it ran (Stop, the end of its session) is MOVE_STATUS_STOPPED.
  void MotionResult(const MoveResult& result, std::uint64_t stops_before, pb::MoveResult* out) {
    ToProto(result, out);
    if (result.status == MoveStatus::kNotSettled && stops.load() != stops_before) {
      out->set_status(pb::MOVE_STATUS_STOPPED);
    }
  }

  // A motion call that arrived when `stop_calls` was `asked` and meets a Stop made since, before
  // its motion starts (it waited for its turn): STOPPED without moving, as the protocol says
  // ("every move started before it, running or waiting, answers STOPPED").
  bool StoppedBeforeStart(std::uint64_t asked, pb::MoveResult* out) {
    if (stop_calls.load() == asked) return false;
    out->set_status(pb::MOVE_STATUS_STOPPED);
    out->set_reason("stopped before the motion started");
    return true;
  }

  void WatchdogLoop() {
    const auto period = std::chrono::duration<double>(
        std::clamp(opt.heartbeat_timeout_s / 10.0, 0.005, 0.05));
    std::unique_lock<std::mutex> lock(watchdog_mutex);
    for (;;) {
      if (watchdog_cv.wait_for(lock, period, [&] { return stopping_watchdog; })) return;
      std::string expired;
      {
        std::lock_guard<std::mutex> s(session_mutex);
        const double silent =
            std::chrono::duration<double>(Clock::now() - last_seen).count();
        if (!live_id.empty() && silent > opt.heartbeat_timeout_s) expired = live_id;
      }
      if (!expired.empty()) {
        std::ostringstream why;
        why << "silent for more than the heartbeat timeout of " << opt.heartbeat_timeout_s
            << " s";
        EndSession(expired, why.str(), true);
      }
      // A task of an ended session still running (it may have started its move just after
      // the stop request): stop it again until it returns.
      // The queue's lock is held across the check and the stop, so that the worker cannot
      // finish that task and start the next session's meanwhile (the stop would land there).
      {
        std::lock_guard<std::mutex> q(queue_mutex);
        if (!running_session.empty() && !IsLive(running_session)) StopMotion();
      }
    }
  }
  bool stopping_watchdog = false;

  // --- the worker --------------------------------------------------------------------------

  void WorkerLoop() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock<std::mutex> lock(queue_mutex);
        queue_cv.wait(lock, [&] { return stopping || !queue.empty(); });
        if (queue.empty()) return;
        task = std::move(queue.front());
        queue.pop_front();
      }
      task();
    }
  }

  // Runs `body` on the worker for session `id` (checked again there) and waits for it. A call
  // cancelled by its client (gone, or past its deadline) before it ran is not run; a motion
  // call cancelled while it runs ends the session and stops the motion.
  Status OnWorker(ServerContext* ctx, const std::string& id, bool motion,
                  const std::function<Status()>& body) {
    auto done = std::make_shared<std::promise<Status>>();
    std::future<Status> result = done->get_future();
    {
      std::lock_guard<std::mutex> lock(queue_mutex);
      if (stopping) return Status(StatusCode::UNAVAILABLE, "the server is shutting down");
      queue.emplace_back([this, ctx, id, &body, done] {
        Status status;
        if (ctx->IsCancelled()) {
          status = Status(StatusCode::CANCELLED, "cancelled before it ran");
        } else if (!id.empty() && !IsLive(id)) {
          status = Status(StatusCode::FAILED_PRECONDITION,
                          "session " + id + " ended before the call ran");
        } else {
          {
            std::lock_guard<std::mutex> q(queue_mutex);
            running_session = id;
          }
          try {
            status = body();
          } catch (const std::exception& e) {
            status = Status(StatusCode::INTERNAL, e.what());
          } catch (...) {
            status = Status(StatusCode::INTERNAL, "unknown exception in the cell");
          }
          std::lock_guard<std::mutex> q(queue_mutex);
          running_session.clear();
        }
        done->set_value(status);
      });
    }
    queue_cv.notify_one();
    bool cancelled_seen = false;
    while (result.wait_for(std::chrono::milliseconds(20)) != std::future_status::ready) {
      if (!cancelled_seen && ctx->IsCancelled()) {
        cancelled_seen = true;
        if (motion) EndSession(id, "its client went away during a motion", true);
      }
    }
    // The call counts as activity when it ends too (a long move is not silence).
    if (!id.empty()) {
      std::lock_guard<std::mutex> lock(session_mutex);
      if (id == live_id) last_seen = Clock::now();
    }
    return result.get();
  }

  // Authorization, the session, then `body` on the worker.
  Status Serve(ServerContext* ctx, const std::string& id, bool motion,
               const std::function<Status()>& body) {
    if (Status s = Authorize(ctx); !s.ok()) return s;
    if (Status s = Touch(id); !s.ok()) return s;
    return OnWorker(ctx, id, motion, body);
  }

  // --- validation --------------------------------------------------------------------------

  std::string BadRobot(std::uint32_t robot) const {
    if (robot < desc.robot_names.size()) return "";
    return "robot index " + std::to_string(robot) + " is not a robot of this cell (it has " +
           std::to_string(desc.robot_names.size()) + ")";
  }

  std::string BadJoints(std::uint32_t robot, const google::protobuf::RepeatedField<double>& q) {
    const std::size_t n = desc.limits[robot].size();
    if (static_cast<std::size_t>(q.size()) != n) {
      return "robot " + std::to_string(robot) + " has " + std::to_string(n) + " joints, got " +
             std::to_string(q.size()) + " targets";
    }
    for (int i = 0; i < q.size(); ++i) {
      if (!std::isfinite(q[i])) {
        return "joint " + std::to_string(i + 1) + " target of robot " + std::to_string(robot) +
               " is not finite";
      }
    }
    return "";
  }

  void Shutdown() {
    std::call_once(shutdown_once, [&] {
      StopMotion();
      {
        std::lock_guard<std::mutex> lock(session_mutex);
        if (!live_id.empty()) NoteEnded(live_id, "the server shut down");
        live_id.clear();
      }
      if (server) server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
      {
        std::lock_guard<std::mutex> lock(queue_mutex);
        stopping = true;
      }
      queue_cv.notify_all();
      if (worker.joinable()) worker.join();
      {
        std::lock_guard<std::mutex> lock(watchdog_mutex);
        stopping_watchdog = true;
      }
      watchdog_cv.notify_all();
      if (watchdog.joinable()) watchdog.join();
    });
  }
};

namespace {

class CellService final : public pb::Cell::Service {
 public:
  explicit CellService(CellServer::Impl& s) : s_(s) {}

  Status Describe(ServerContext* ctx, const pb::DescribeRequest*,
                  pb::DescribeResponse* out) override {
    if (Status st = s_.Authorize(ctx); !st.ok()) return st;
    const CellDescription& d = s_.desc;
    out->set_protocol_version(1);
    out->set_cell_name(d.cell_name);
    for (std::size_t k = 0; k < d.robot_names.size(); ++k) {
      pb::RobotDescription* r = out->add_robots();
      r->set_name(d.robot_names[k]);
      for (const JointLimits& lim : d.limits[k]) {
        pb::JointLimit* j = r->add_joints();
        j->set_lower_rad(lim.lower);
        j->set_upper_rad(lim.upper);
      }
    }
    out->set_has_camera(d.has_camera);
    out->set_image_width_px(static_cast<std::uint32_t>(d.image_width_px));
    out->set_image_height_px(static_cast<std::uint32_t>(d.image_height_px));
    out->set_has_tracker(d.has_tracker);
    out->set_has_handclasp(d.has_handclasp);
    out->set_has_clock(d.has_clock);
    out->set_heartbeat_timeout_s(s_.opt.heartbeat_timeout_s);
    out->set_server("twinbench cell server (protocol v1)");
    return Status::OK;
  }

  Status OpenSession(ServerContext* ctx, const pb::OpenSessionRequest* req,
                     pb::OpenSessionResponse* out) override {
    if (Status st = s_.Authorize(ctx); !st.ok()) return st;
    std::lock_guard<std::mutex> lock(s_.session_mutex);
    if (!s_.live_id.empty()) {
      // The id is the holder's capability: only its first 8 of 32 digits are named.
      return Status(StatusCode::FAILED_PRECONDITION,
                    "the cell is held by session " + s_.live_id.substr(0, 8) + "... (client '" +
                        s_.live_client + "'); it ends with CloseSession or after " +
                        std::to_string(s_.opt.heartbeat_timeout_s) + " s of silence");
    }
    s_.live_id = NewSessionId();
    s_.live_client = req->client().substr(0, 200);
    s_.last_seen = Clock::now();
    out->set_session_id(s_.live_id);
    out->set_heartbeat_timeout_s(s_.opt.heartbeat_timeout_s);
    return Status::OK;
  }

  Status Heartbeat(ServerContext* ctx, const pb::HeartbeatRequest* req,
                   pb::HeartbeatResponse*) override {
    if (Status st = s_.Authorize(ctx); !st.ok()) return st;
    return s_.Touch(req->session_id());
  }

  Status CloseSession(ServerContext* ctx, const pb::CloseSessionRequest* req,
                      pb::CloseSessionResponse*) override {
    if (Status st = s_.Authorize(ctx); !st.ok()) return st;
    if (Status st = s_.Touch(req->session_id()); !st.ok()) return st;
    s_.EndSession(req->session_id(), "closed by its client", false);
    return Status::OK;
  }

  Status Stop(ServerContext* ctx, const pb::StopRequest* req, pb::StopResponse*) override {
    if (Status st = s_.Authorize(ctx); !st.ok()) return st;
    if (Status st = s_.Touch(req->session_id()); !st.ok()) return st;
    ++s_.stop_calls;
    s_.StopMotion();
    return Status::OK;
  }

  Status MoveTo(ServerContext* ctx, const pb::MoveToRequest* req, pb::MoveResult* out) override {
    const std::uint64_t asked = s_.stop_calls.load();
    return s_.Serve(ctx, req->session_id(), true, [&]() -> Status {
      if (std::string bad = s_.BadRobot(req->robot()); !bad.empty()) return Invalid(bad);
      if (std::string bad = s_.BadJoints(req->robot(), req->q_target_rad()); !bad.empty()) {
        return Invalid(bad);
      }
      const JointVector q = JointsFromProto(req->q_target_rad());
      if (s_.StoppedBeforeStart(asked, out)) return Status::OK;
      const std::uint64_t stops = s_.stops.load();
      s_.MotionResult(s_.cell.MoveTo(static_cast<int>(req->robot()), q), stops, out);
      return Status::OK;
    });
  }

  Status ReadEncoders(ServerContext* ctx, const pb::ReadEncodersRequest* req,
                      pb::ReadEncodersResponse* out) override {
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      if (std::string bad = s_.BadRobot(req->robot()); !bad.empty()) return Invalid(bad);
      JointsToProto(s_.cell.ReadEncoders(static_cast<int>(req->robot())), out->mutable_q_rad());
      return Status::OK;
    });
  }

  Status GrabImage(ServerContext* ctx, const pb::GrabImageRequest* req,
                   pb::GrabImageResponse* out) override {
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      if (!s_.desc.has_camera) {
        return Status(StatusCode::UNIMPLEMENTED, "this cell has no hand camera");
      }
      if (!req->has_region()) {
        EncodeImage(s_.cell.GrabImage(), 0, 0, out, req->encoding());
        return Status::OK;
      }
      const pb::PixelRegion& r = req->region();
      if (r.width_px() <= 0 || r.height_px() <= 0) {
        return Invalid("an image region needs a positive width and height, got " +
                       std::to_string(r.width_px()) + " x " + std::to_string(r.height_px()));
      }
      if (r.x_px() < -kMaxRegionCoordinate || r.x_px() > kMaxRegionCoordinate ||
          r.y_px() < -kMaxRegionCoordinate || r.y_px() > kMaxRegionCoordinate ||
          r.width_px() > kMaxRegionCoordinate || r.height_px() > kMaxRegionCoordinate) {
        return Invalid("image region numbers beyond " + std::to_string(kMaxRegionCoordinate) +
                       " px");
      }
      const cv::Rect roi(r.x_px(), r.y_px(), r.width_px(), r.height_px());
      const cv::Rect clipped = roi & cv::Rect(0, 0, s_.desc.image_width_px,
                                              s_.desc.image_height_px);
      const cv::Mat image = s_.cell.GrabImageRegion(roi);
      EncodeImage(image, clipped.empty() ? roi.x : clipped.x, clipped.empty() ? roi.y : clipped.y,
                  out, req->encoding());
      return Status::OK;
    });
  }

  Status ExchangeTools(ServerContext* ctx, const pb::ExchangeToolsRequest* req,
                       pb::MoveResult* out) override {
    const std::uint64_t asked = s_.stop_calls.load();
    return s_.Serve(ctx, req->session_id(), true, [&]() -> Status {
      if (!s_.desc.has_camera) {
        return Status(StatusCode::UNIMPLEMENTED, "this cell has no hand camera");
      }
      if (s_.StoppedBeforeStart(asked, out)) return Status::OK;
      const std::uint64_t stops = s_.stops.load();
      s_.MotionResult(s_.cell.ExchangeTools(), stops, out);
      return Status::OK;
    });
  }

  Status CameraRobot(ServerContext* ctx, const pb::CameraRobotRequest* req,
                     pb::CameraRobotResponse* out) override {
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      if (!s_.desc.has_camera) {
        return Status(StatusCode::UNIMPLEMENTED, "this cell has no hand camera");
      }
      out->set_robot(static_cast<std::uint32_t>(s_.cell.CameraRobot()));
      return Status::OK;
    });
  }

  Status JogTipToContact(ServerContext* ctx, const pb::JogTipToContactRequest* req,
                         pb::MoveResult* out) override {
    const std::uint64_t asked = s_.stop_calls.load();
    return s_.Serve(ctx, req->session_id(), true, [&]() -> Status {
      if (std::string bad = s_.BadRobot(req->jogged_robot()); !bad.empty()) return Invalid(bad);
      if (s_.StoppedBeforeStart(asked, out)) return Status::OK;
      const std::uint64_t stops = s_.stops.load();
      s_.MotionResult(s_.cell.JogTipToContact(static_cast<int>(req->jogged_robot())), stops, out);
      return Status::OK;
    });
  }

  Status MountTarget(ServerContext* ctx, const pb::MountTargetRequest* req,
                     pb::MoveResult* out) override {
    const std::uint64_t asked = s_.stop_calls.load();
    return s_.Serve(ctx, req->session_id(), true, [&]() -> Status {
      BracketTarget target;
      try {
        target = FromProto(req->target());
      } catch (const std::exception& e) {
        return Invalid(e.what());
      }
      if (s_.StoppedBeforeStart(asked, out)) return Status::OK;
      const std::uint64_t stops = s_.stops.load();
      s_.MotionResult(s_.cell.MountTarget(target), stops, out);
      return Status::OK;
    });
  }

  Status ReadClock(ServerContext* ctx, const pb::ReadClockRequest* req,
                   pb::ReadClockResponse* out) override {
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      const double t = s_.cell.ClockSeconds();
      out->set_has_clock(std::isfinite(t));
      out->set_time_s(std::isfinite(t) ? t : 0.0);
      return Status::OK;
    });
  }

  Status ReadTemperature(ServerContext* ctx, const pb::ReadTemperatureRequest* req,
                         pb::ReadTemperatureResponse* out) override {
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      if (std::string bad = s_.BadRobot(req->robot()); !bad.empty()) return Invalid(bad);
      const double c = s_.cell.ReadTemperatureC(static_cast<int>(req->robot()));
      out->set_has_sensor(std::isfinite(c));
      out->set_temperature_deg_c(std::isfinite(c) ? c : 0.0);
      return Status::OK;
    });
  }

  Status MeasureTracker(ServerContext* ctx, const pb::MeasureTrackerRequest* req,
                        pb::MeasureTrackerResponse* out) override {
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      if (std::string bad = s_.BadRobot(req->robot()); !bad.empty()) return Invalid(bad);
      ToProto(s_.cell.MeasureTracker(static_cast<int>(req->robot())), out);
      return Status::OK;
    });
  }

 private:
  CellServer::Impl& s_;
};

class TruthService final : public bpb::TwinBench::Service {
 public:
  explicit TruthService(CellServer::Impl& s) : s_(s) {}
  Status Truth(ServerContext* ctx, const bpb::TruthRequest* req, bpb::TwinTruth* out) override {
    if (!s_.opt.truth) {
      if (Status st = s_.Authorize(ctx); !st.ok()) return st;
      return Status(StatusCode::UNIMPLEMENTED, "this cell offers no truth (serve-cell --no-truth "
                                               "or a real cell)");
    }
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      ToProto(s_.opt.truth(), out);
      return Status::OK;
    });
  }

  Status SetOperatorError(ServerContext* ctx, const bpb::OperatorErrorRequest* req,
                          bpb::OperatorErrorResponse*) override {
    if (!s_.opt.set_operator_error) {
      if (Status st = s_.Authorize(ctx); !st.ok()) return st;
      return Status(StatusCode::UNIMPLEMENTED, "this cell has no simulated operator (serve-cell "
                                               "--no-truth or a real cell)");
    }
    return s_.Serve(ctx, req->session_id(), false, [&]() -> Status {
      const double sigma = req->alignment_sigma_m();
      if (!(sigma >= 0.0 && sigma <= kMaxOperatorSigmaM)) {
        return Invalid("alignment_sigma_m must be within 0 to " +
                       std::to_string(kMaxOperatorSigmaM) + " m, got " + std::to_string(sigma));
      }
      s_.opt.set_operator_error(sigma);
      return Status::OK;
    });
  }

 private:
  CellServer::Impl& s_;
};

// The server's credentials for `opt`; throws InputError for what the options lack.
std::shared_ptr<grpc::ServerCredentials> ServerCredentialsFor(const ServerOptions& opt) {
  const bool tls = !opt.tls_cert_file.empty() || !opt.tls_key_file.empty();
  if (tls && (opt.tls_cert_file.empty() || opt.tls_key_file.empty())) {
    throw InputError("--tls-cert/--tls-key", "TLS needs both the certificate and its key");
  }
  if (!opt.client_ca_file.empty() && !tls) {
    throw InputError("--client-ca", "client certificates need TLS (--tls-cert and --tls-key)");
  }
  if (!IsLoopbackAddress(opt.listen) &&
      (!tls || (opt.client_ca_file.empty() && opt.token_file.empty()))) {
    throw InputError("--listen", "'" + opt.listen + "' is beyond loopback: serving there needs "
                                 "TLS (--tls-cert, --tls-key) and client authentication "
                                 "(--client-ca or --token-file)");
  }
  if (!tls) return grpc::InsecureServerCredentials();
  grpc::SslServerCredentialsOptions ssl(GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  grpc::SslServerCredentialsOptions::PemKeyCertPair pair;
  pair.cert_chain = ReadFileOrThrow(opt.tls_cert_file, "--tls-cert");
  pair.private_key = ReadFileOrThrow(opt.tls_key_file, "--tls-key");
  ssl.pem_key_cert_pairs.push_back(pair);
  if (!opt.client_ca_file.empty()) {
    ssl.pem_root_certs = ReadFileOrThrow(opt.client_ca_file, "--client-ca");
    ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(ssl);
}

}  // namespace

std::string TokenOfText(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!line.empty() && blank(line.back())) line.pop_back();
  std::size_t start = 0;
  while (start < line.size() && blank(line[start])) ++start;
  return line.substr(start);
}

CellServer::CellServer(Cell& cell, CellDescription description, ServerOptions options)
    : impl_(std::make_unique<Impl>(cell, std::move(description), std::move(options))) {
  Impl& s = *impl_;
  if (!(s.opt.heartbeat_timeout_s > 0.0) || !std::isfinite(s.opt.heartbeat_timeout_s)) {
    throw InputError("--heartbeat-timeout", "expected a positive number of seconds");
  }
  if (s.desc.limits.size() != s.desc.robot_names.size()) {
    throw std::logic_error("CellDescription: one joint-limit list per robot");
  }
  const auto credentials = ServerCredentialsFor(s.opt);
  if (!s.opt.token_file.empty()) s.token = ReadToken(s.opt.token_file, "--token-file");
  s.cell_service = std::make_unique<CellService>(s);
  s.truth_service = std::make_unique<TruthService>(s);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(s.opt.listen, credentials, &s.port);
  builder.RegisterService(s.cell_service.get());
  builder.RegisterService(s.truth_service.get());
  builder.SetMaxReceiveMessageSize(4 << 20);
  s.server = builder.BuildAndStart();
  if (!s.server || s.port == 0) {
    throw InputError("--listen", "cannot listen on '" + s.opt.listen + "'");
  }
  s.worker = std::thread([&s] { s.WorkerLoop(); });
  s.watchdog = std::thread([&s] { s.WatchdogLoop(); });
}

CellServer::~CellServer() { impl_->Shutdown(); }

int CellServer::BoundPort() const { return impl_->port; }

void CellServer::Wait() { impl_->server->Wait(); }

void CellServer::Shutdown() { impl_->Shutdown(); }

}  // namespace twin::remote
