#include "bench/runs/replay_cell.h"

#include <filesystem>
#include <limits>

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>

#include "bench/io/yaml_util.h"
#include "bench/runs/recording_cell.h"
#include "calib/common/errors.h"
#include "remote/proto_convert.h"

namespace twin {

namespace fs = std::filesystem;
namespace pb = remote::pb;
namespace bpb = remote::bpb;

namespace {

// The message of a recorded JSON text; throws InputError naming `where`.
void ParseMessage(const std::string& json, const std::string& where,
                  google::protobuf::Message* message, bool ignore_unknown = false) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = ignore_unknown;
  const auto status = google::protobuf::util::JsonStringToMessage(json, message, options);
  if (!status.ok()) {
    throw InputError(where, "not a " + message->GetTypeName() + ": " +
                                std::string(status.message()));
  }
}

// Equal to the bit: the deterministic wire form of both (a double is its 8 bytes there).
bool SameMessage(const google::protobuf::Message& a, const google::protobuf::Message& b) {
  std::string sa, sb;
  {
    google::protobuf::io::StringOutputStream out(&sa);
    google::protobuf::io::CodedOutputStream coded(&out);
    coded.SetSerializationDeterministic(true);
    a.SerializeToCodedStream(&coded);
  }
  {
    google::protobuf::io::StringOutputStream out(&sb);
    google::protobuf::io::CodedOutputStream coded(&out);
    coded.SetSerializationDeterministic(true);
    b.SerializeToCodedStream(&coded);
  }
  return sa == sb;
}

// What differs between the asked and the recorded request, field by field ("" where the
// differencer sees none: a -0 against a 0).
std::string Differences(const google::protobuf::Message& asked,
                        const google::protobuf::Message& recorded) {
  std::string report;
  google::protobuf::util::MessageDifferencer differencer;
  differencer.ReportDifferencesToString(&report);
  differencer.Compare(recorded, asked);
  while (!report.empty() && report.back() == '\n') report.pop_back();
  for (char& c : report) {
    if (c == '\n') c = ';';
  }
  return report.empty() ? "" : " (recorded -> asked: " + report + ")";
}

[[noreturn]] void Bad(const std::exception& e, const std::string& where) {
  throw InputError(where, std::string("the recorded response: ") + e.what());
}

}  // namespace

RecordingManifest ReadRecordingManifest(const std::string& dir) {
  const std::string path = (fs::path(dir) / kRecordingManifestFile).string();
  if (!fs::is_regular_file(path)) {
    throw InputError(dir, std::string("not a recording: no ") + kRecordingManifestFile +
                              " (`twinbench run --record` writes one)");
  }
  return ParseRecordingManifest(ReadTextFile(path), path);
}

ReplayCell::ReplayCell(const std::string& dir)
    : dir_(dir), file_((fs::path(dir) / kRecordingExchangesFile).string()) {
  manifest_ = ReadRecordingManifest(dir);
  const std::string text = ReadTextFile(file_, std::numeric_limits<std::uintmax_t>::max());
  size_t start = 0;
  long line_number = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    ++line_number;
    const std::string where = file_ + ":" + std::to_string(line_number);
    if (line.empty()) continue;
    RecordedExchange e = ParseRecordedExchangeLine(line, where);
    if (e.seq != static_cast<long>(exchanges_.size()) + 1) {
      throw InputError(where, "seq " + std::to_string(e.seq) + " where " +
                                  std::to_string(exchanges_.size() + 1) +
                                  " was expected (lines lost or out of order)");
    }
    exchanges_.push_back(std::move(e));
  }
}

void ReplayCell::Next(const char* method, const google::protobuf::Message& request,
                      google::protobuf::Message* response) {
  const std::string asked = std::string(method) + " " + RecordingJson(request);
  const long total = recorded();
  if (next_ >= exchanges_.size()) {
    throw InputError(file_, "the recording ended at seq " + std::to_string(total) +
                                ", and the replay asked for more: " + asked +
                                Truncation());
  }
  const RecordedExchange& e = exchanges_[next_];
  const std::string where = file_ + ":" + std::to_string(e.seq) + " (seq " +
                            std::to_string(e.seq) + ")";
  std::unique_ptr<google::protobuf::Message> recorded(request.New());
  bool same = e.method == method;
  std::string differences;
  if (same) {
    ParseMessage(e.request_json, where + " request", recorded.get());
    same = SameMessage(request, *recorded);
    if (!same) differences = Differences(request, *recorded);
  }
  if (!same) {
    throw InputError(where, "the estimator asked " + asked + ", the recording has " + e.method +
                                " " + e.request_json + differences +
                                ": the replayed procedure diverged from the recorded one "
                                "(other options, code or scenario)");
  }
  ParseMessage(e.response_json, where + " response", response);
  if (!e.image_file.empty()) {
    auto* image = dynamic_cast<pb::GrabImageResponse*>(response);
    if (!image) throw InputError(where, "an image_file in a " + e.method + " response");
    const std::string png = (fs::path(dir_) / e.image_file).string();
    image->set_data(ReadTextFile(png, std::numeric_limits<std::uintmax_t>::max()));
  }
  ++next_;
}

std::string ReplayCell::Truncation() const {
  if (!manifest_.complete) return " (a partial recording: its run stopped there)";
  if (manifest_.exchanges > recorded()) {
    return " (" + std::string(kRecordingManifestFile) + " counts " +
           std::to_string(manifest_.exchanges) + " exchanges: the file lost its last lines)";
  }
  return " (the replayed procedure diverged from the recorded one: other options, code or "
         "scenario)";
}

MoveResult ReplayCell::MoveTo(int robot, const JointVector& q) {
  pb::MoveToRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  remote::JointsToProto(q, request.mutable_q_target_rad());
  pb::MoveResult response;
  Next("MoveTo", request, &response);
  return remote::FromProto(response);
}

JointVector ReplayCell::ReadEncoders(int robot) {
  pb::ReadEncodersRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  pb::ReadEncodersResponse response;
  Next("ReadEncoders", request, &response);
  return remote::JointsFromProto(response.q_rad());
}

cv::Mat ReplayCell::NextImage(const cv::Rect* roi) {
  pb::GrabImageRequest request;
  if (roi) remote::RegionToProto(*roi, request.mutable_region());
  pb::GrabImageResponse response;
  Next("GrabImage", request, &response);
  try {
    return remote::DecodeImage(response);
  } catch (const remote::ProtocolError& e) {
    Bad(e, file_ + ":" + std::to_string(next_));
  }
}

cv::Mat ReplayCell::GrabImage() { return NextImage(nullptr); }
cv::Mat ReplayCell::GrabImageRegion(const cv::Rect& roi) { return NextImage(&roi); }

MoveResult ReplayCell::ExchangeTools() {
  pb::MoveResult response;
  Next("ExchangeTools", pb::ExchangeToolsRequest(), &response);
  return remote::FromProto(response);
}

int ReplayCell::CameraRobot() {
  pb::CameraRobotResponse response;
  Next("CameraRobot", pb::CameraRobotRequest(), &response);
  return static_cast<int>(response.robot());
}

MoveResult ReplayCell::JogTipToContact(int jogged_robot) {
  pb::JogTipToContactRequest request;
  request.set_jogged_robot(static_cast<uint32_t>(jogged_robot));
  pb::MoveResult response;
  Next("JogTipToContact", request, &response);
  return remote::FromProto(response);
}

MoveResult ReplayCell::MountTarget(BracketTarget target) {
  pb::MountTargetRequest request;
  request.set_target(remote::ToProto(target));
  pb::MoveResult response;
  Next("MountTarget", request, &response);
  return remote::FromProto(response);
}

double ReplayCell::ClockSeconds() {
  pb::ReadClockResponse response;
  Next("ReadClock", pb::ReadClockRequest(), &response);
  return response.has_clock() ? response.time_s() : std::numeric_limits<double>::quiet_NaN();
}

double ReplayCell::ReadTemperatureC(int robot) {
  pb::ReadTemperatureRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  pb::ReadTemperatureResponse response;
  Next("ReadTemperature", request, &response);
  return response.has_sensor() ? response.temperature_deg_c()
                               : std::numeric_limits<double>::quiet_NaN();
}

TrackerReading ReplayCell::MeasureTracker(int robot) {
  pb::MeasureTrackerRequest request;
  request.set_robot(static_cast<uint32_t>(robot));
  pb::MeasureTrackerResponse response;
  Next("MeasureTracker", request, &response);
  return remote::FromProto(response);
}

bool ReplayCell::HasTruth() {
  for (const RecordedExchange& e : exchanges_) {
    if (e.method == "Truth") return true;
  }
  return false;
}

TwinTruth ReplayCell::Truth() {
  bpb::TwinTruth response;
  Next("Truth", bpb::TruthRequest(), &response);
  try {
    return remote::FromProto(response);
  } catch (const remote::ProtocolError& e) {
    Bad(e, file_ + ":" + std::to_string(next_));
  }
}

bool ReplayCell::SetOperatorAlignmentError(double sigma_m) {
  if (next_ >= exchanges_.size() || exchanges_[next_].method != "SetOperatorError") return false;
  bpb::OperatorErrorRequest request;
  request.set_alignment_sigma_m(sigma_m);
  bpb::OperatorErrorResponse response;
  Next("SetOperatorError", request, &response);
  return true;
}

void ReplayCell::Finish() {
  if (next_ == exchanges_.size()) return;
  throw InputError(file_, "the replay ended at seq " + std::to_string(next_) + " of " +
                              std::to_string(recorded()) +
                              ": the replayed procedure made fewer calls than the recorded one "
                              "(it diverged: other options, code or scenario)");
}

}  // namespace twin
