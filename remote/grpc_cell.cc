// The cell protocol's client (remote/grpc_cell.h).
#include "remote/grpc_cell.h"

#include "remote/cell_server.h"  // IsLoopbackAddress

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

std::string Describe(const char* method, const grpc::Status& status) {
  return std::string(method) + ": " + StatusText(status);
}

}  // namespace

struct GrpcCell::Impl {
  // The truth channel's answer into `resp`: OK, or UNIMPLEMENTED (a cell without truth); any
  // other status is thrown naming the cell.
  grpc::Status AskTruth(bpb::TwinTruth* resp);
  std::string where;
  GrpcCellDeadlines deadlines;
  std::string authorization;  // "Bearer <token>" or empty
  // Images: raw RGB on loopback (no PNG to encode and decode: the link is memory), PNG beyond.
  std::string image_encoding = "png";
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
  CellChannel channel = OpenCellChannel(address, credentials, where);
  if (IsLoopbackAddress(address)) s.image_encoding = "rgb8";
  s.channel = std::move(channel.channel);
  s.authorization = std::move(channel.authorization);
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
  req.set_encoding(s.image_encoding);
  pb::GrabImageResponse resp;
  s.Call("GrabImage", &pb::Cell::Stub::GrabImage, req, &resp, s.deadlines.image_s);
  return DecodeImage(resp);
}

cv::Mat GrpcCell::GrabImageRegion(const cv::Rect& roi) {
  Impl& s = *impl_;
  if (roi.width <= 0 || roi.height <= 0) return cv::Mat();  // misses every frame
  pb::GrabImageRequest req;
  req.set_session_id(s.session);
  req.set_encoding(s.image_encoding);
  RegionToProto(roi, req.mutable_region());
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

grpc::Status GrpcCell::Impl::AskTruth(bpb::TwinTruth* resp) {
  Impl& s = *this;
  bpb::TruthRequest req;
  req.set_session_id(s.session);
  grpc::ClientContext ctx;
  s.Prepare(&ctx, s.deadlines.call_s);
  const grpc::Status status = s.truth_stub->Truth(&ctx, req, resp);
  if (!status.ok() && status.error_code() != grpc::UNIMPLEMENTED) {
    throw std::runtime_error(s.where + ": " + Describe("Truth", status));
  }
  return status;
}

TwinTruth GrpcCell::Truth() {
  Impl& s = *impl_;
  bpb::TwinTruth resp;
  const grpc::Status status = s.AskTruth(&resp);
  if (status.error_code() == grpc::UNIMPLEMENTED) {
    throw InputError(s.where, "the cell offers no truth to score against (" +
                                  status.error_message() + ")");
  }
  return FromProto(resp);
}

bool GrpcCell::HasTruth() {
  bpb::TwinTruth resp;
  return impl_->AskTruth(&resp).ok();
}

bool GrpcCell::SetOperatorAlignmentError(double sigma_m) {
  Impl& s = *impl_;
  bpb::OperatorErrorRequest req;
  req.set_session_id(s.session);
  req.set_alignment_sigma_m(sigma_m);
  bpb::OperatorErrorResponse resp;
  grpc::ClientContext ctx;
  s.Prepare(&ctx, s.deadlines.call_s);
  const grpc::Status status = s.truth_stub->SetOperatorError(&ctx, req, &resp);
  if (status.error_code() == grpc::UNIMPLEMENTED) return false;
  if (!status.ok()) throw std::runtime_error(s.where + ": " + Describe("SetOperatorError", status));
  return true;
}

const std::string& GrpcCell::session_id() const { return impl_->session; }

const std::string& GrpcCell::cell_name() const { return impl_->description.cell_name(); }

}  // namespace twin::remote
