#include "remote/cell_check.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

#include <grpcpp/grpcpp.h>
#include <opencv2/imgcodecs.hpp>

#include "calib/common/errors.h"
#include "remote/cell_channel.h"
#include "twinbench/cell/v1/cell.grpc.pb.h"

namespace twin::remote {

namespace {

namespace pb = ::twinbench::cell::v1;
using Clock = std::chrono::steady_clock;
using Seconds = std::chrono::duration<double>;

constexpr double kCallSeconds = 10.0;    // deadline of a call that does not move anything
constexpr double kMoveSeconds = 120.0;   // deadline of a move
// Two encoder readings of a robot at rest agree within this [rad]: 1 mrad is far above the
// encoder noise of any shipped scenario (1e-5 rad order) and far below what a unit error
// (degrees for radians: a factor of 57) or a robot still moving shows.
constexpr double kAtRestRad = 1e-3;
// The small move of the units check [rad]: 50 mrad, 50 times kAtRestRad.
constexpr double kStepRad = 0.05;
// A joint limit beyond this is not in radians (two turns each way) [rad].
constexpr double kMaxLimitRad = 4 * 3.14159265358979323846;

std::string Status(const grpc::Status& s) { return StatusText(s); }

std::string Joints(const google::protobuf::RepeatedField<double>& q) {
  std::ostringstream s;
  s.precision(4);
  s << "[";
  for (int i = 0; i < q.size(); ++i) s << (i ? ", " : "") << q.Get(i);
  return s.str() + "]";
}

double MaxDifference(const google::protobuf::RepeatedField<double>& a,
                     const google::protobuf::RepeatedField<double>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double d = 0;
  for (int i = 0; i < a.size(); ++i) d = std::max(d, std::abs(a.Get(i) - b.Get(i)));
  return std::isfinite(d) ? d : std::numeric_limits<double>::infinity();
}

// The connection and the battery's state: the cell as described, the live session, and a
// heartbeat thread that keeps it alive between the checks' calls (paused for the checks that
// need the client silent).
class Battery {
 public:
  Battery(const CellCheckOptions& o, std::ostream& out) : o_(o), out_(out) {
    const std::string prefix = "grpc://";
    if (o.address.rfind(prefix, 0) != 0 || o.address.size() == prefix.size()) {
      throw InputError(o.address, "a cell address is grpc://HOST:PORT");
    }
    target_ = o.address.substr(prefix.size());
    credentials_ = GrpcCellCredentials{o.tls_ca_file, o.tls_cert_file, o.tls_key_file,
                                       o.token_file};
    // The token's metadata, once (the heartbeat thread reads it from then on).
    authorization_ = OpenCellChannel(target_, credentials_, o.address).authorization;
    stub_ = NewStub();
  }

  ~Battery() { StopHeartbeat(); }

  std::vector<CheckLine> Run() {
    Describe();
    Sessions();
    Encoders();
    Malformed();
    if (o_.allow_motion) {
      UnitsMove();
      OutOfLimits();
    } else {
      for (const char* n : {"units: a move", "refusal outside the limits"}) {
        Add(n, CheckOutcome::kSkip, "moves a robot: run with --allow-motion, the cell clear");
      }
    }
    ClockCheck();
    Image();
    Silence();
    if (o_.allow_motion) {
      StopOnDisconnect();
    } else {
      Add("stop on disconnect", CheckOutcome::kSkip,
          "moves a robot: run with --allow-motion, the cell clear");
    }
    StopHeartbeat();
    if (!session_.empty()) {
      pb::CloseSessionRequest req;
      req.set_session_id(session_);
      pb::CloseSessionResponse resp;
      auto ctx = Context(kCallSeconds);
      stub_->CloseSession(ctx.get(), req, &resp);
    }
    return lines_;
  }

 private:
  // A stub on a connection of its own: the stop check's call must not share the battery's.
  std::unique_ptr<pb::Cell::Stub> NewStub() {
    return pb::Cell::NewStub(OpenCellChannel(target_, credentials_, o_.address, true).channel);
  }

  std::unique_ptr<grpc::ClientContext> Context(double seconds) const {
    auto ctx = std::make_unique<grpc::ClientContext>();
    ctx->set_deadline(std::chrono::system_clock::now() +
                      std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000)));
    if (!authorization_.empty()) ctx->AddMetadata("authorization", authorization_);
    return ctx;
  }

  void Add(const std::string& name, CheckOutcome outcome, const std::string& detail) {
    lines_.push_back({name, outcome, detail});
    const char* tag = outcome == CheckOutcome::kPass   ? "PASS"
                      : outcome == CheckOutcome::kFail ? "FAIL"
                                                       : "SKIP";
    out_ << tag << "  " << name << ": " << detail << "\n";
    out_.flush();
  }

  void Pass(const std::string& name, const std::string& detail) {
    Add(name, CheckOutcome::kPass, detail);
  }
  void Fail(const std::string& name, const std::string& detail) {
    Add(name, CheckOutcome::kFail, detail);
  }
  /// Passes with `detail` when `problems` is empty, else fails with them joined by "; ".
  void PassUnless(const std::string& name, const std::vector<std::string>& problems,
                  const std::string& detail) {
    if (problems.empty()) return Pass(name, detail);
    std::string all;
    for (const std::string& w : problems) all += (all.empty() ? "" : "; ") + w;
    Fail(name, all);
  }

  // --- heartbeat of the battery's session -------------------------------------------------
  void StartHeartbeat() {
    StopHeartbeat();
    beating_ = true;
    const double period = std::max(0.02, heartbeat_timeout_s_ / 4);
    heartbeat_ = std::thread([this, period] {
      std::unique_lock<std::mutex> lock(beat_mutex_);
      while (beating_) {
        pb::HeartbeatRequest req;
        req.set_session_id(session_);
        lock.unlock();
        pb::HeartbeatResponse resp;
        auto ctx = Context(kCallSeconds);
        stub_->Heartbeat(ctx.get(), req, &resp);
        lock.lock();
        beat_cv_.wait_for(lock, Seconds(period), [this] { return !beating_; });
      }
    });
  }

  void StopHeartbeat() {
    {
      std::lock_guard<std::mutex> lock(beat_mutex_);
      beating_ = false;
    }
    beat_cv_.notify_all();
    if (heartbeat_.joinable()) heartbeat_.join();
  }

  grpc::Status Open(pb::Cell::Stub& stub, std::string* id) {
    pb::OpenSessionRequest req;
    req.set_client("twinbench cell-check");
    pb::OpenSessionResponse resp;
    auto ctx = Context(kCallSeconds);
    const grpc::Status s = stub.OpenSession(ctx.get(), req, &resp);
    if (s.ok()) *id = resp.session_id();
    return s;
  }

  grpc::Status Read(const std::string& session, int robot, pb::ReadEncodersResponse* resp) {
    pb::ReadEncodersRequest req;
    req.set_session_id(session);
    req.set_robot(static_cast<uint32_t>(robot));
    auto ctx = Context(kCallSeconds);
    return stub_->ReadEncoders(ctx.get(), req, resp);
  }

  grpc::Status Move(const std::string& session, int robot,
                    const google::protobuf::RepeatedField<double>& q, pb::MoveResult* result) {
    pb::MoveToRequest req;
    req.set_session_id(session);
    req.set_robot(static_cast<uint32_t>(robot));
    *req.mutable_q_target_rad() = q;
    auto ctx = Context(kMoveSeconds);
    return stub_->MoveTo(ctx.get(), req, result);
  }

  const pb::RobotDescription& Robot() const { return describe_.robots(o_.robot); }

  // --- the checks -------------------------------------------------------------------------
  void Describe() {
    pb::DescribeRequest req;
    auto ctx = Context(kCallSeconds);
    const grpc::Status s = stub_->Describe(ctx.get(), req, &describe_);
    if (!s.ok()) throw InputError(o_.address, "Describe: " + Status(s));
    std::vector<std::string> wrong;
    if (describe_.protocol_version() != 1) {
      wrong.push_back("protocol_version " + std::to_string(describe_.protocol_version()) +
                      ", this client speaks 1");
    }
    if (describe_.robots_size() < 1 || describe_.robots_size() > 2) {
      wrong.push_back(std::to_string(describe_.robots_size()) + " robots (1 or 2)");
    }
    double largest = 0;
    for (const pb::RobotDescription& r : describe_.robots()) {
      if (r.joints_size() < 1 || r.joints_size() > 12) {
        wrong.push_back("robot '" + r.name() + "' has " + std::to_string(r.joints_size()) +
                        " joints (1..12)");
      }
      for (const pb::JointLimit& l : r.joints()) {
        if (!std::isfinite(l.lower_rad()) || !std::isfinite(l.upper_rad()) ||
            l.lower_rad() >= l.upper_rad()) {
          wrong.push_back("robot '" + r.name() + "' has a joint with limits " +
                          std::to_string(l.lower_rad()) + " .. " + std::to_string(l.upper_rad()));
        }
        largest = std::max({largest, std::abs(l.lower_rad()), std::abs(l.upper_rad())});
      }
    }
    heartbeat_timeout_s_ = describe_.heartbeat_timeout_s();
    if (!(heartbeat_timeout_s_ > 0 && heartbeat_timeout_s_ <= 60)) {
      wrong.push_back("heartbeat_timeout_s " + std::to_string(heartbeat_timeout_s_) +
                      " (0 < t <= 60 s)");
      heartbeat_timeout_s_ = 2.0;
    }
    if (describe_.has_camera() &&
        (describe_.image_width_px() == 0 || describe_.image_height_px() == 0)) {
      wrong.push_back("a camera without an image size");
    }
    if (o_.robot < 0 || o_.robot >= describe_.robots_size()) {
      throw InputError("--robot", "the cell has " + std::to_string(describe_.robots_size()) +
                                      " robots; --robot " + std::to_string(o_.robot));
    }
    PassUnless("describe", wrong,
               "protocol 1, " + std::to_string(describe_.robots_size()) +
                   " robot(s), heartbeat timeout " + std::to_string(heartbeat_timeout_s_) +
                   " s, server '" + describe_.server() + "'");
    if (largest <= kMaxLimitRad) {
      Pass("units: limits in rad", "largest |limit| " + std::to_string(largest) + " rad");
    } else {
      Fail("units: limits in rad",
           "a joint limit of " + std::to_string(largest) +
               ": beyond two turns, not radians (degrees?)");
    }
  }

  void Sessions() {
    grpc::Status s = Open(*stub_, &session_);
    if (!s.ok() || session_.empty()) {
      Fail("sessions", "OpenSession: " + Status(s));
      throw InputError(o_.address, "OpenSession refused: " + Status(s) +
                                       " (is another client holding the cell?)");
    }
    StartHeartbeat();
    std::string second;
    const grpc::Status again = Open(*NewStub(), &second);
    pb::ReadEncodersResponse resp;
    const grpc::Status wrong_id = Read(session_ + "-not-mine", o_.robot, &resp);
    const grpc::Status no_id = Read("", o_.robot, &resp);
    std::vector<std::string> bad;
    if (again.error_code() != grpc::StatusCode::FAILED_PRECONDITION) {
      bad.push_back("a second OpenSession while one is alive: " + Status(again) +
                    ", expected FAILED_PRECONDITION");
    }
    if (wrong_id.error_code() != grpc::StatusCode::FAILED_PRECONDITION) {
      bad.push_back("a call naming another session: " + Status(wrong_id) +
                    ", expected FAILED_PRECONDITION");
    }
    if (no_id.error_code() != grpc::StatusCode::FAILED_PRECONDITION) {
      bad.push_back("a call naming no session: " + Status(no_id) +
                    ", expected FAILED_PRECONDITION");
    }
    PassUnless("sessions", bad, "one client at a time; calls outside the session refused");
  }

  void Encoders() {
    pb::ReadEncodersResponse resp;
    const grpc::Status s = Read(session_, o_.robot, &resp);
    if (!s.ok()) return Fail("encoders", "ReadEncoders: " + Status(s));
    start_ = resp.q_rad();
    if (resp.q_rad_size() != Robot().joints_size()) {
      return Fail("encoders", std::to_string(resp.q_rad_size()) + " readings for " +
                                  std::to_string(Robot().joints_size()) + " joints");
    }
    for (int i = 0; i < resp.q_rad_size(); ++i) {
      const double q = resp.q_rad(i);
      const pb::JointLimit& l = Robot().joints(i);
      if (!std::isfinite(q) || q < l.lower_rad() - kAtRestRad || q > l.upper_rad() + kAtRestRad) {
        return Fail("encoders", "joint " + std::to_string(i + 1) + " reads " +
                                    std::to_string(q) + " outside its limits " +
                                    std::to_string(l.lower_rad()) + " .. " +
                                    std::to_string(l.upper_rad()) + " (units?)");
      }
    }
    Pass("encoders", "robot " + std::to_string(o_.robot) + " at " + Joints(start_) + " rad");
  }

  // Requests the protocol calls malformed: each must be refused with INVALID_ARGUMENT, and
  // nothing may move.
  void Malformed() {
    std::vector<std::string> bad;
    auto expect = [&](const char* what, const grpc::Status& s) {
      if (s.error_code() != grpc::StatusCode::INVALID_ARGUMENT) {
        bad.push_back(std::string(what) + ": " + Status(s) + ", expected INVALID_ARGUMENT");
      }
    };
    pb::ReadEncodersResponse enc;
    expect("ReadEncoders of a robot the cell lacks",
           Read(session_, describe_.robots_size(), &enc));
    // Malformed motion calls: a server that does not check them might move the robot, so
    // they are sent only with --allow-motion.
    if (o_.allow_motion) {
      pb::MoveResult moved;
      google::protobuf::RepeatedField<double> q = start_;
      q.Add(0.0);
      expect("MoveTo with one joint too many", Move(session_, o_.robot, q, &moved));
      q = start_;
      if (q.size() > 0) q.Set(0, std::numeric_limits<double>::quiet_NaN());
      expect("MoveTo with NaN", Move(session_, o_.robot, q, &moved));
      if (q.size() > 0) q.Set(0, std::numeric_limits<double>::infinity());
      expect("MoveTo with infinity", Move(session_, o_.robot, q, &moved));
      pb::MountTargetRequest req;
      req.set_session_id(session_);
      req.set_target(static_cast<pb::BracketTarget>(99));
      pb::MoveResult r;
      auto ctx = Context(kCallSeconds);
      expect("MountTarget of target 99", stub_->MountTarget(ctx.get(), req, &r));
    }
    if (describe_.has_camera()) {
      pb::GrabImageRequest req;
      req.set_session_id(session_);
      req.mutable_region()->set_width_px(0);
      req.mutable_region()->set_height_px(10);
      pb::GrabImageResponse r;
      auto ctx = Context(kCallSeconds);
      expect("GrabImage of an empty region", stub_->GrabImage(ctx.get(), req, &r));
    }
    const grpc::Status s = Read(session_, o_.robot, &enc);
    if (s.ok() && MaxDifference(enc.q_rad(), start_) > kAtRestRad) {
      bad.push_back("the robot moved: " + Joints(start_) + " -> " + Joints(enc.q_rad()));
    }
    PassUnless("malformed requests", bad,
               o_.allow_motion ? "refused with INVALID_ARGUMENT, nothing moved"
                               : "refused with INVALID_ARGUMENT, nothing moved (the malformed "
                                 "MoveTo and MountTarget calls need --allow-motion)");
  }

  // The last joint by kStepRad and back: the readings must follow in radians.
  void UnitsMove() {
    const char* name = "units: a move";
    if (start_.empty()) return Add(name, CheckOutcome::kSkip, "no encoder reading");
    const int j = start_.size() - 1;
    const pb::JointLimit& l = Robot().joints(j);
    google::protobuf::RepeatedField<double> target = start_;
    const double up = start_.Get(j) + kStepRad;
    target.Set(j, up <= l.upper_rad() - kAtRestRad ? up : start_.Get(j) - kStepRad);
    pb::MoveResult moved;
    grpc::Status s = Move(session_, o_.robot, target, &moved);
    if (!s.ok()) return Fail(name, "MoveTo: " + Status(s));
    if (moved.status() != pb::MOVE_STATUS_SETTLED) {
      return Fail(name, "MoveTo by " + std::to_string(kStepRad) + " rad did not settle: " +
                            pb::MoveStatus_Name(moved.status()) + " " + moved.reason());
    }
    pb::ReadEncodersResponse enc;
    s = Read(session_, o_.robot, &enc);
    const double off = s.ok() ? MaxDifference(enc.q_rad(), target)
                              : std::numeric_limits<double>::infinity();
    pb::MoveResult back;
    Move(session_, o_.robot, start_, &back);
    if (off > kAtRestRad) {
      return Fail(name, "after MoveTo " + Joints(target) + " rad the encoders read " +
                            Joints(enc.q_rad()) + " (off by " + std::to_string(off) +
                            "; degrees for radians?)");
    }
    Pass(name, "joint " + std::to_string(j + 1) + " moved " + std::to_string(kStepRad) +
                   " rad; the reading is within " + std::to_string(off) + " rad of it");
  }

  void OutOfLimits() {
    const char* name = "refusal outside the limits";
    if (start_.empty()) return Add(name, CheckOutcome::kSkip, "no encoder reading");
    google::protobuf::RepeatedField<double> target = start_;
    target.Set(0, Robot().joints(0).upper_rad() + 0.1);
    pb::MoveResult moved;
    const grpc::Status s = Move(session_, o_.robot, target, &moved);
    pb::ReadEncodersResponse enc;
    Read(session_, o_.robot, &enc);
    const double d = MaxDifference(enc.q_rad(), start_);
    if (!s.ok() && s.error_code() != grpc::StatusCode::INVALID_ARGUMENT) {
      return Fail(name, "MoveTo beyond joint 1's upper limit: " + Status(s));
    }
    if (s.ok() && moved.status() != pb::MOVE_STATUS_OUT_OF_LIMITS) {
      return Fail(name, "MoveTo 0.1 rad beyond joint 1's upper limit answered " +
                            pb::MoveStatus_Name(moved.status()) +
                            ", expected MOVE_STATUS_OUT_OF_LIMITS");
    }
    if (d > kAtRestRad) {
      return Fail(name, "the robot moved by " + std::to_string(d) + " rad on a refused move");
    }
    Pass(name, "0.1 rad beyond joint 1's upper limit: refused, nothing moved");
  }

  void ClockCheck() {
    const char* name = "monotonic clock";
    if (!describe_.has_clock()) return Add(name, CheckOutcome::kSkip, "the cell keeps no clock");
    double last = -std::numeric_limits<double>::infinity();
    int reads = 0;
    for (int i = 0; i < 50; ++i) {
      pb::ReadClockRequest req;
      req.set_session_id(session_);
      pb::ReadClockResponse resp;
      auto ctx = Context(kCallSeconds);
      const grpc::Status s = stub_->ReadClock(ctx.get(), req, &resp);
      if (!s.ok()) return Fail(name, "ReadClock: " + Status(s));
      if (!resp.has_clock() || !std::isfinite(resp.time_s())) {
        return Fail(name, "Describe says the cell has a clock; ReadClock answered none");
      }
      if (resp.time_s() < last) {
        return Fail(name, "the clock went back from " + std::to_string(last) + " s to " +
                              std::to_string(resp.time_s()) + " s at read " +
                              std::to_string(i + 1));
      }
      last = resp.time_s();
      ++reads;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    Pass(name, std::to_string(reads) + " reads 10 ms apart never went back");
  }

  void Image() {
    const char* name = "image format";
    if (!describe_.has_camera()) return Add(name, CheckOutcome::kSkip, "the cell has no camera");
    pb::GrabImageRequest req;
    req.set_session_id(session_);
    pb::GrabImageResponse resp;
    auto ctx = Context(60);
    grpc::Status s = stub_->GrabImage(ctx.get(), req, &resp);
    if (!s.ok()) return Fail(name, "GrabImage: " + Status(s));
    const std::vector<uchar> bytes(resp.data().begin(), resp.data().end());
    const cv::Mat image =
        resp.encoding() == "png" ? cv::imdecode(bytes, cv::IMREAD_UNCHANGED) : cv::Mat();
    const uint32_t w = describe_.image_width_px(), h = describe_.image_height_px();
    if (image.empty()) {
      return Fail(name, "the frame does not decode as png (encoding '" + resp.encoding() +
                            "', " + std::to_string(bytes.size()) + " bytes)");
    }
    if (image.depth() != CV_8U || image.channels() != 3) {
      return Fail(name, "the frame is not 8-bit with 3 channels");
    }
    if (static_cast<uint32_t>(image.cols) != w || static_cast<uint32_t>(image.rows) != h ||
        resp.width_px() != w || resp.height_px() != h) {
      return Fail(name, "a frame of " + std::to_string(image.cols) + "x" +
                            std::to_string(image.rows) + " px; Describe says " +
                            std::to_string(w) + "x" + std::to_string(h));
    }
    // A region in the middle: its own size, at its own offset.
    pb::GrabImageRequest region_req;
    region_req.set_session_id(session_);
    pb::PixelRegion* r = region_req.mutable_region();
    r->set_x_px(static_cast<int>(w / 4));
    r->set_y_px(static_cast<int>(h / 4));
    r->set_width_px(static_cast<int>(std::max(1u, w / 4)));
    r->set_height_px(static_cast<int>(std::max(1u, h / 4)));
    pb::GrabImageResponse region;
    auto ctx2 = Context(60);
    s = stub_->GrabImage(ctx2.get(), region_req, &region);
    if (!s.ok()) return Fail(name, "GrabImage of a region: " + Status(s));
    const std::vector<uchar> rbytes(region.data().begin(), region.data().end());
    const cv::Mat part = cv::imdecode(rbytes, cv::IMREAD_UNCHANGED);
    if (part.empty() || part.cols != r->width_px() || part.rows != r->height_px() ||
        region.x_px() != r->x_px() || region.y_px() != r->y_px()) {
      return Fail(name, "a region of " + std::to_string(r->width_px()) + "x" +
                            std::to_string(r->height_px()) + " px at (" +
                            std::to_string(r->x_px()) + ", " + std::to_string(r->y_px()) +
                            ") came back as " + std::to_string(part.cols) + "x" +
                            std::to_string(part.rows) + " at (" + std::to_string(region.x_px()) +
                            ", " + std::to_string(region.y_px()) + ")");
    }
    Pass(name, "png, 8-bit, 3 channels, " + std::to_string(w) + "x" + std::to_string(h) +
                   " px; a region comes back at its size and offset");
  }

  // Silent for longer than the heartbeat timeout: the session must end.
  void Silence() {
    const char* name = "silence ends the session";
    StopHeartbeat();
    std::this_thread::sleep_for(Seconds(1.5 * heartbeat_timeout_s_ + 0.2));
    pb::ReadEncodersResponse enc;
    const grpc::Status s = Read(session_, o_.robot, &enc);
    std::string fresh;
    const grpc::Status opened = Open(*stub_, &fresh);
    if (opened.ok()) {
      session_ = fresh;
      StartHeartbeat();
    }
    if (s.error_code() != grpc::StatusCode::FAILED_PRECONDITION) {
      return Fail(name, "after " + std::to_string(1.5 * heartbeat_timeout_s_ + 0.2) +
                            " s of silence the old session still answers: " + Status(s));
    }
    if (!opened.ok()) return Fail(name, "no new session after the old one ended: " + Status(opened));
    Pass(name, "refused after " + std::to_string(1.5 * heartbeat_timeout_s_ + 0.2) +
                   " s of silence; a new session opened");
  }

  // A long move of joint 1 from a client that then disappears: the robot must stop short.
  void StopOnDisconnect() {
    const char* name = "stop on disconnect";
    if (start_.empty()) return Add(name, CheckOutcome::kSkip, "no encoder reading");
    pb::ReadEncodersResponse enc;
    if (!Read(session_, o_.robot, &enc).ok()) return Fail(name, "ReadEncoders failed");
    const google::protobuf::RepeatedField<double> from = enc.q_rad();
    const pb::JointLimit& l = Robot().joints(0);
    google::protobuf::RepeatedField<double> target = from;
    const double room_up = l.upper_rad() - from.Get(0), room_down = from.Get(0) - l.lower_rad();
    const double step = std::min(o_.stop_move_rad, 0.9 * std::max(room_up, room_down));
    target.Set(0, from.Get(0) + (room_up >= room_down ? step : -step));
    // Hand the cell to a client of its own connection, which then goes silent mid-move.
    StopHeartbeat();
    pb::CloseSessionRequest close;
    close.set_session_id(session_);
    pb::CloseSessionResponse closed;
    auto ctx0 = Context(kCallSeconds);
    stub_->CloseSession(ctx0.get(), close, &closed);
    session_.clear();
    std::unique_ptr<pb::Cell::Stub> doomed = NewStub();
    std::string doomed_session;
    if (!Open(*doomed, &doomed_session).ok()) return Fail(name, "OpenSession for the move failed");
    pb::MoveToRequest req;
    req.set_session_id(doomed_session);
    req.set_robot(static_cast<uint32_t>(o_.robot));
    *req.mutable_q_target_rad() = target;
    auto move_ctx = Context(kMoveSeconds);
    pb::MoveResult result;
    std::atomic<bool> returned{false};
    grpc::ClientContext* move_context = move_ctx.get();
    std::thread mover([&] {
      doomed->MoveTo(move_context, req, &result);
      returned = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const bool settled_early = returned.load();
    move_context->TryCancel();  // the client is gone: no answer awaited, no heartbeat
    mover.join();
    const auto t_gone = Clock::now();
    if (settled_early) {
      // The move's client is still here: it closes its session and the battery's takes over.
      pb::CloseSessionRequest done;
      done.set_session_id(doomed_session);
      auto ctx1 = Context(kCallSeconds);
      doomed->CloseSession(ctx1.get(), done, &closed);
      const grpc::Status reopened = Open(*stub_, &session_);
      if (!reopened.ok()) return Fail(name, "no session after the move: " + Status(reopened));
      StartHeartbeat();
      pb::MoveResult back;
      Move(session_, o_.robot, from, &back);
      return Add(name, CheckOutcome::kSkip,
                 "the move of " + std::to_string(step) +
                     " rad ended within 0.3 s, before the client went away; a cell that "
                     "moves in real time is needed (serve-cell --realtime)");
    }
    // A new session must open once the server has noticed (heartbeat timeout and a margin of
    // 1 s for its watchdog and the network).
    const double limit_s = heartbeat_timeout_s_ + 1.0;
    grpc::Status opened;
    std::string fresh;
    while (Seconds(Clock::now() - t_gone).count() < limit_s) {
      opened = Open(*stub_, &fresh);
      if (opened.ok()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (!opened.ok()) {
      return Fail(name, "no new session within " + std::to_string(limit_s) +
                            " s of the client going away: " + Status(opened));
    }
    session_ = fresh;
    StartHeartbeat();
    pb::ReadEncodersResponse a, b;
    Read(session_, o_.robot, &a);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    Read(session_, o_.robot, &b);
    const double drift = MaxDifference(a.q_rad(), b.q_rad());
    const double short_by = std::abs(b.q_rad_size() > 0 ? b.q_rad(0) - target.Get(0) : 0.0);
    pb::MoveResult back;
    Move(session_, o_.robot, from, &back);
    if (drift > kAtRestRad) {
      return Fail(name, "the robot still moves after its client went away (" +
                            std::to_string(drift) + " rad in 0.3 s)");
    }
    if (short_by <= kAtRestRad) {
      return Fail(name, "the robot went on to the target after its client went away");
    }
    Pass(name, "stopped " + std::to_string(short_by) + " rad short of the target; a new "
                   "session opened within " + std::to_string(limit_s) + " s");
  }

  const CellCheckOptions& o_;
  std::ostream& out_;
  std::string target_, authorization_;
  GrpcCellCredentials credentials_;
  std::unique_ptr<pb::Cell::Stub> stub_;
  pb::DescribeResponse describe_;
  double heartbeat_timeout_s_ = 2.0;
  std::string session_;
  google::protobuf::RepeatedField<double> start_;
  std::vector<CheckLine> lines_;
  std::thread heartbeat_;
  std::mutex beat_mutex_;
  std::condition_variable beat_cv_;
  bool beating_ = false;
};

}  // namespace

std::vector<CheckLine> RunCellCheck(const CellCheckOptions& options, std::ostream& out) {
  Battery battery(options, out);
  return battery.Run();
}

int RunCellCheckVerb(const CellCheckOptions& options) {
  std::printf("twinbench cell-check %s\n", options.address.c_str());
  std::fflush(stdout);
  const std::vector<CheckLine> lines = RunCellCheck(options, std::cout);
  int failed = 0, skipped = 0;
  for (const CheckLine& l : lines) {
    failed += l.outcome == CheckOutcome::kFail;
    skipped += l.outcome == CheckOutcome::kSkip;
  }
  std::printf("cell-check: %d checks, %d failed, %d skipped: %s\n",
              static_cast<int>(lines.size()), failed, skipped, failed ? "FAIL" : "PASS");
  return failed ? 1 : 0;
}

}  // namespace twin::remote
