#include "bench/runs/recording_cell.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>

#include <google/protobuf/util/json_util.h>

#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "calib/common/errors.h"
#include "remote/proto_convert.h"

namespace twin {

namespace fs = std::filesystem;
namespace pb = remote::pb;
namespace bpb = remote::bpb;

namespace {

// Protobuf prints a negative zero as -0 but reads -0 back as +0 (an integer token); -0.0 reads
// back as the negative zero. Rewrites every number token -0 (outside strings) as -0.0.
std::string KeepNegativeZeros(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  bool in_string = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    out += c;
    if (in_string) {
      if (c == '\\') {
        if (++i < json.size()) out += json[i];
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '-' && i + 1 < json.size() && json[i + 1] == '0' &&
               (i + 2 == json.size() || std::strchr(",]} ", json[i + 2]) != nullptr)) {
      out += "0.0";
      ++i;
    }
  }
  return out;
}

}  // namespace

std::string RecordingJson(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string text;
  const auto status = google::protobuf::util::MessageToJsonString(message, &text, options);
  if (!status.ok()) {
    throw std::runtime_error("protobuf JSON of " + message.GetTypeName() + ": " +
                             std::string(status.message()));
  }
  return KeepNegativeZeros(text);
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

RecordingCell::RecordingCell(std::unique_ptr<BenchCell> inner, const std::string& dir,
                             const RecordingManifest& manifest)
    : ForwardingBenchCell(std::move(inner)), dir_(dir), manifest_(manifest), t0_(Clock::now()) {
  // A new folder only: create_directory fails on anything that exists (no race with a check).
  std::error_code ec;
  const fs::path parent = fs::path(dir).parent_path();
  if (!parent.empty()) fs::create_directories(parent, ec);
  if (!fs::create_directory(dir, ec)) {
    throw InputError("--record", "'" + dir + "' " +
                                     (ec ? "cannot be created: " + ec.message()
                                         : std::string("exists; a recording goes into a new "
                                                       "folder")));
  }
  fs::create_directory(fs::path(dir) / kRecordingImagesFolder);
  if (manifest_.started_utc.empty()) manifest_.started_utc = UtcNow();
  WriteTextFile((fs::path(dir) / kRecordingManifestFile).string(),
                RecordingManifestText(manifest_));
  const std::string path = (fs::path(dir) / kRecordingExchangesFile).string();
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(path, std::string("cannot be created: ") + std::strerror(errno));
}

RecordingCell::~RecordingCell() {
  if (fd_ >= 0) ::close(fd_);
}

void RecordingCell::Append(const char* method, Clock::time_point t_call,
                           const google::protobuf::Message& request,
                           const google::protobuf::Message& response, const std::string& png) {
  const std::lock_guard<std::mutex> lock(mutex_);
  RecordedExchange e;
  e.seq = ++seq_;
  e.method = method;
  e.t_wall_s = std::chrono::duration<double>(t_call - t0_).count();
  e.request_json = RecordingJson(request);
  e.response_json = RecordingJson(response);
  if (!png.empty()) {
    char name[32];
    std::snprintf(name, sizeof(name), "%s/%06ld.png", kRecordingImagesFolder, e.seq);
    e.image_file = name;
    WriteTextFile((fs::path(dir_) / name).string(), png);
  }
  // One write per line, straight to the file: what is recorded survives a crash of the run.
  if (!WriteAll(fd_, RecordedExchangeLine(e) + "\n")) {
    throw InputError((fs::path(dir_) / kRecordingExchangesFile).string(),
                     std::string("writing the recording failed: ") + std::strerror(errno));
  }
}

MoveResult RecordingCell::MoveTo(int robot, const JointVector& q) {
  const Clock::time_point t = Clock::now();
  const MoveResult result = inner_.MoveTo(robot, q);
  pb::MoveToRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  remote::JointsToProto(q, request.mutable_q_target_rad());
  pb::MoveResult response;
  remote::ToProto(result, &response);
  Append("MoveTo", t, request, response);
  return result;
}

JointVector RecordingCell::ReadEncoders(int robot) {
  const Clock::time_point t = Clock::now();
  const JointVector q = inner_.ReadEncoders(robot);
  pb::ReadEncodersRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  pb::ReadEncodersResponse response;
  remote::JointsToProto(q, response.mutable_q_rad());
  Append("ReadEncoders", t, request, response);
  return q;
}

// Records a GrabImage exchange of `image` (frame pixel (x, y) at its (0, 0)); roi: the region
// asked for (null: the whole frame).
cv::Mat RecordingCell::RecordImage(const cv::Mat& image, int x, int y, Clock::time_point t,
                                   const cv::Rect* roi) {
  pb::GrabImageRequest request;
  if (roi) remote::RegionToProto(*roi, request.mutable_region());
  pb::GrabImageResponse response;
  remote::EncodeImage(image, x, y, &response);
  const std::string png = response.data();
  response.clear_data();
  Append("GrabImage", t, request, response, png);
  return image;
}

cv::Mat RecordingCell::GrabImage() {
  const Clock::time_point t = Clock::now();
  return RecordImage(inner_.GrabImage(), 0, 0, t, nullptr);
}

cv::Mat RecordingCell::GrabImageRegion(const cv::Rect& roi) {
  const Clock::time_point t = Clock::now();
  const cv::Mat image = inner_.GrabImageRegion(roi);
  // The image's pixel (0, 0) is the clipped region's top left corner.
  return RecordImage(image, std::max(roi.x, 0), std::max(roi.y, 0), t, &roi);
}

MoveResult RecordingCell::ExchangeTools() {
  const Clock::time_point t = Clock::now();
  const MoveResult result = inner_.ExchangeTools();
  pb::MoveResult response;
  remote::ToProto(result, &response);
  Append("ExchangeTools", t, pb::ExchangeToolsRequest(), response);
  return result;
}

int RecordingCell::CameraRobot() {
  const Clock::time_point t = Clock::now();
  const int robot = inner_.CameraRobot();
  pb::CameraRobotResponse response;
  response.set_robot(static_cast<uint32_t>(robot));
  Append("CameraRobot", t, pb::CameraRobotRequest(), response);
  return robot;
}

MoveResult RecordingCell::JogTipToContact(int jogged_robot) {
  const Clock::time_point t = Clock::now();
  const MoveResult result = inner_.JogTipToContact(jogged_robot);
  pb::JogTipToContactRequest request;
  request.set_jogged_robot(static_cast<uint32_t>(jogged_robot));
  pb::MoveResult response;
  remote::ToProto(result, &response);
  Append("JogTipToContact", t, request, response);
  return result;
}

MoveResult RecordingCell::MountTarget(BracketTarget target) {
  const Clock::time_point t = Clock::now();
  const MoveResult result = inner_.MountTarget(target);
  pb::MountTargetRequest request;
  request.set_target(remote::ToProto(target));
  pb::MoveResult response;
  remote::ToProto(result, &response);
  Append("MountTarget", t, request, response);
  return result;
}

double RecordingCell::ClockSeconds() {
  const Clock::time_point t = Clock::now();
  const double time_s = inner_.ClockSeconds();
  pb::ReadClockResponse response;
  response.set_has_clock(!std::isnan(time_s));
  if (!std::isnan(time_s)) response.set_time_s(time_s);
  Append("ReadClock", t, pb::ReadClockRequest(), response);
  return time_s;
}

double RecordingCell::ReadTemperatureC(int robot) {
  const Clock::time_point t = Clock::now();
  const double c = inner_.ReadTemperatureC(robot);
  pb::ReadTemperatureRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  pb::ReadTemperatureResponse response;
  response.set_has_sensor(!std::isnan(c));
  if (!std::isnan(c)) response.set_temperature_deg_c(c);
  Append("ReadTemperature", t, request, response);
  return c;
}

TrackerReading RecordingCell::MeasureTracker(int robot) {
  const Clock::time_point t = Clock::now();
  const TrackerReading reading = inner_.MeasureTracker(robot);
  pb::MeasureTrackerRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  pb::MeasureTrackerResponse response;
  remote::ToProto(reading, &response);
  Append("MeasureTracker", t, request, response);
  return reading;
}

TwinTruth RecordingCell::Truth() {
  const Clock::time_point t = Clock::now();
  const TwinTruth truth = inner_.Truth();
  bpb::TwinTruth response;
  remote::ToProto(truth, &response);
  Append("Truth", t, bpb::TruthRequest(), response);
  return truth;
}

bool RecordingCell::SetOperatorAlignmentError(double sigma_m) {
  const Clock::time_point t = Clock::now();
  if (!inner_.SetOperatorAlignmentError(sigma_m)) return false;
  bpb::OperatorErrorRequest request;
  request.set_alignment_sigma_m(sigma_m);
  Append("SetOperatorError", t, request, bpb::OperatorErrorResponse());
  return true;
}

void RecordingCell::Finish() {
  ForwardingBenchCell::Finish();
  const std::lock_guard<std::mutex> lock(mutex_);
  manifest_.complete = true;
  manifest_.exchanges = seq_;
  manifest_.ended_utc = UtcNow();
  WriteFileAtomically((fs::path(dir_) / kRecordingManifestFile).string(),
                      RecordingManifestText(manifest_));
}

}  // namespace twin
