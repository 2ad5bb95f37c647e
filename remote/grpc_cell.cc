// The cell protocol's client (remote/grpc_cell.h).
#include "remote/grpc_cell.h"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "calib/common/errors.h"
#include "remote/proto_convert.h"
#include "twinbench/bench/v1/truth.grpc.pb.h"
#include "twinbench/cell/v1/cell.grpc.pb.h"

namespace twin::remote {

namespace {

std::string ReadFile(const std::string& path, const std::string& where, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where, "cannot read the " + what + " '" + path + "'");
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::string FirstLineTrimmed(const std::string& text) {
  std::string line = text.substr(0, text.find('\n'));
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!line.empty() && blank(line.back())) line.pop_back();
  std::size_t start = 0;
  while (start < line.size() && blank(line[start])) ++start;
  return line.substr(start);
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

std::string Describe(const char* method, const grpc::Status& status) {
  return std::string(method) + ": " + CodeName(status.error_code()) + ": " +
         status.error_message();
}

}  // namespace

struct GrpcCell::Impl {
  std::string where;
  GrpcCellDeadlines deadlines;
  std::string authorization;  // "Bearer <token>" or empty
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<pb::Cell::Stub> stub;
  std::unique_ptr<bpb::TwinBench::Stub> truth_stub;
  pb::DescribeResponse description;
  std::string session;
  double heartbeat_timeout_s = 2.0;
  std::thread heartbeat;
  std::mutex heartbeat_mutex;
  std::condition_variable heartbeat_cv;
  bool closing = false;

  void Prepare(grpc::ClientContext* ctx, double deadline_s) const {
    ctx->set_deadline(std::chrono::system_clock::now() +
                      std::chrono::duration_cast<std::chrono::system_clock::duration>(
                          std::chrono::duration<double>(deadline_s)));
    if (!authorization.empty()) ctx->AddMetadata("authorization", authorization);
  }

  // Calls stub method `fn`; a refusal throws runtime_error (InputError naming `where` when
  // `setup`).
  template <class Req, class Resp, class Fn>
  void Call(const char* method, Fn fn, const Req& req, Resp* resp, double deadline_s,
            bool setup = false) {
    grpc::ClientContext ctx;
    Prepare(&ctx, deadline_s);
    const grpc::Status status = ((*stub).*fn)(&ctx, req, resp);
    if (status.ok()) return;
    if (setup) throw InputError(where, Describe(method, status));
    throw std::runtime_error(where + ": " + Describe(method, status));
  }

  void HeartbeatLoop() {
    const auto period = std::chrono::duration<double>(heartbeat_timeout_s / 4.0);
    std::unique_lock<std::mutex> lock(heartbeat_mutex);
    while (!heartbeat_cv.wait_for(lock, period, [&] { return closing; })) {
      lock.unlock();
      pb::HeartbeatRequest req;
      req.set_session_id(session);
      pb::HeartbeatResponse resp;
      grpc::ClientContext ctx;
      Prepare(&ctx, std::max(heartbeat_timeout_s, 1.0));
      (void)stub->Heartbeat(&ctx, req, &resp);  // a lost session shows at the next call
      lock.lock();
    }
  }
};

GrpcCell::GrpcCell(const std::string& address, const GrpcCellCredentials& credentials,
                   const std::string& where, GrpcCellDeadlines deadlines)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.where = where;
  s.deadlines = deadlines;
  std::shared_ptr<grpc::ChannelCredentials> channel_credentials;
  if (!credentials.ca_file.empty() || !credentials.cert_file.empty() ||
      !credentials.key_file.empty()) {
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
    const std::string token = FirstLineTrimmed(
        ReadFile(credentials.token_file, where, "token file (--cell-token-file)"));
    if (token.empty()) throw InputError(where, "the token file holds no token on its first line");
    s.authorization = "Bearer " + token;
  }
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(256 << 20);
  s.channel = grpc::CreateCustomChannel(address, channel_credentials, args);
  s.stub = pb::Cell::NewStub(s.channel);
  s.truth_stub = bpb::TwinBench::NewStub(s.channel);

  s.Call("Describe", &pb::Cell::Stub::Describe, pb::DescribeRequest(), &s.description,
         deadlines.call_s, true);
  if (s.description.protocol_version() != 1) {
    throw InputError(where, "the cell speaks protocol version " +
                                std::to_string(s.description.protocol_version()) +
                                "; this twinbench speaks 1");
  }
  pb::OpenSessionRequest open;
  open.set_client("twinbench");
  pb::OpenSessionResponse opened;
  s.Call("OpenSession", &pb::Cell::Stub::OpenSession, open, &opened, deadlines.call_s, true);
  s.session = opened.session_id();
  if (opened.heartbeat_timeout_s() > 0 && std::isfinite(opened.heartbeat_timeout_s())) {
    s.heartbeat_timeout_s = opened.heartbeat_timeout_s();
  }
  s.heartbeat = std::thread([&s] { s.HeartbeatLoop(); });
}

GrpcCell::~GrpcCell() {
  Impl& s = *impl_;
  {
    std::lock_guard<std::mutex> lock(s.heartbeat_mutex);
    s.closing = true;
  }
  s.heartbeat_cv.notify_all();
  if (s.heartbeat.joinable()) s.heartbeat.join();
  try {
    pb::CloseSessionRequest req;
    req.set_session_id(s.session);
    pb::CloseSessionResponse resp;
    grpc::ClientContext ctx;
    s.Prepare(&ctx, 5.0);
    (void)s.stub->CloseSession(&ctx, req, &resp);
  } catch (...) {
  }
}

MoveResult GrpcCell::MoveTo(int robot, const JointVector& q_target) {
  Impl& s = *impl_;
  pb::MoveToRequest req;
  req.set_session_id(s.session);
  req.set_robot(static_cast<std::uint32_t>(robot));
  JointsToProto(q_target, req.mutable_q_target_rad());
  pb::MoveResult resp;
  s.Call("MoveTo", &pb::Cell::Stub::MoveTo, req, &resp, s.deadlines.motion_s);
  return FromProto(resp);
}

JointVector GrpcCell::ReadEncoders(int robot) {
  Impl& s = *impl_;
  pb::ReadEncodersRequest req;
  req.set_session_id(s.session);
  req.set_robot(static_cast<std::uint32_t>(robot));
  pb::ReadEncodersResponse resp;
  s.Call("ReadEncoders", &pb::Cell::Stub::ReadEncoders, req, &resp, s.deadlines.call_s);
  return JointsFromProto(resp.q_rad());
}

cv::Mat GrpcCell::GrabImage() {
  Impl& s = *impl_;
  pb::GrabImageRequest req;
  req.set_session_id(s.session);
  pb::GrabImageResponse resp;
  s.Call("GrabImage", &pb::Cell::Stub::GrabImage, req, &resp, s.deadlines.image_s);
  return DecodeImage(resp);
}

cv::Mat GrpcCell::GrabImageRegion(const cv::Rect& roi) {
  Impl& s = *impl_;
  if (roi.width <= 0 || roi.height <= 0) return cv::Mat();  // misses every frame
  pb::GrabImageRequest req;
  req.set_session_id(s.session);
  pb::PixelRegion* region = req.mutable_region();
  region->set_x_px(roi.x);
  region->set_y_px(roi.y);
  region->set_width_px(roi.width);
  region->set_height_px(roi.height);
  pb::GrabImageResponse resp;
  s.Call("GrabImage", &pb::Cell::Stub::GrabImage, req, &resp, s.deadlines.image_s);
  return DecodeImage(resp);
}

MoveResult GrpcCell::ExchangeTools() {
  Impl& s = *impl_;
  pb::ExchangeToolsRequest req;
  req.set_session_id(s.session);
  pb::MoveResult resp;
  s.Call("ExchangeTools", &pb::Cell::Stub::ExchangeTools, req, &resp, s.deadlines.motion_s);
  return FromProto(resp);
}

int GrpcCell::CameraRobot() {
  Impl& s = *impl_;
  pb::CameraRobotRequest req;
  req.set_session_id(s.session);
  pb::CameraRobotResponse resp;
  s.Call("CameraRobot", &pb::Cell::Stub::CameraRobot, req, &resp, s.deadlines.call_s);
  return static_cast<int>(resp.robot());
}

MoveResult GrpcCell::JogTipToContact(int jogged_robot) {
  Impl& s = *impl_;
  pb::JogTipToContactRequest req;
  req.set_session_id(s.session);
  req.set_jogged_robot(static_cast<std::uint32_t>(jogged_robot));
  pb::MoveResult resp;
  s.Call("JogTipToContact", &pb::Cell::Stub::JogTipToContact, req, &resp, s.deadlines.motion_s);
  return FromProto(resp);
}

MoveResult GrpcCell::MountTarget(BracketTarget target) {
  Impl& s = *impl_;
  pb::MountTargetRequest req;
  req.set_session_id(s.session);
  req.set_target(ToProto(target));
  pb::MoveResult resp;
  s.Call("MountTarget", &pb::Cell::Stub::MountTarget, req, &resp, s.deadlines.motion_s);
  return FromProto(resp);
}

double GrpcCell::ClockSeconds() {
  Impl& s = *impl_;
  pb::ReadClockRequest req;
  req.set_session_id(s.session);
  pb::ReadClockResponse resp;
  s.Call("ReadClock", &pb::Cell::Stub::ReadClock, req, &resp, s.deadlines.call_s);
  return resp.has_clock() ? resp.time_s() : std::numeric_limits<double>::quiet_NaN();
}

double GrpcCell::ReadTemperatureC(int robot) {
  Impl& s = *impl_;
  pb::ReadTemperatureRequest req;
  req.set_session_id(s.session);
  req.set_robot(static_cast<std::uint32_t>(robot));
  pb::ReadTemperatureResponse resp;
  s.Call("ReadTemperature", &pb::Cell::Stub::ReadTemperature, req, &resp, s.deadlines.call_s);
  return resp.has_sensor() ? resp.temperature_deg_c()
                           : std::numeric_limits<double>::quiet_NaN();
}

TrackerReading GrpcCell::MeasureTracker(int robot) {
  Impl& s = *impl_;
  pb::MeasureTrackerRequest req;
  req.set_session_id(s.session);
  req.set_robot(static_cast<std::uint32_t>(robot));
  pb::MeasureTrackerResponse resp;
  s.Call("MeasureTracker", &pb::Cell::Stub::MeasureTracker, req, &resp, s.deadlines.call_s);
  return FromProto(resp);
}

TwinTruth GrpcCell::Truth() {
  Impl& s = *impl_;
  bpb::TruthRequest req;
  req.set_session_id(s.session);
  bpb::TwinTruth resp;
  grpc::ClientContext ctx;
  s.Prepare(&ctx, s.deadlines.call_s);
  const grpc::Status status = s.truth_stub->Truth(&ctx, req, &resp);
  if (status.error_code() == grpc::UNIMPLEMENTED) {
    throw InputError(s.where, "the cell offers no truth to score against (" +
                                  status.error_message() + ")");
  }
  if (!status.ok()) throw std::runtime_error(s.where + ": " + Describe("Truth", status));
  return FromProto(resp);
}

const std::string& GrpcCell::session_id() const { return impl_->session; }

const std::string& GrpcCell::cell_name() const { return impl_->description.cell_name(); }

}  // namespace twin::remote
