// `twinbench run --record RDIR`: a BenchCell that passes every call on to the cell it wraps and
// appends the exchange to a recording (bench/report/recording_file.h, docs/reference/recording.md)
// as it happens, each line written through to the file at once: a run that fails midway leaves
// a partial recording of everything up to the failure. `twinbench replay` plays it back
// (bench/runs/replay_cell.h).
#pragma once

#include <chrono>
#include <memory>
#include <mutex>
#include <string>

#include <google/protobuf/message.h>

#include "bench/report/recording_file.h"
#include "bench/runs/bench_cell.h"

namespace twin {

class RecordingCell : public ForwardingBenchCell {
 public:
  /// Creates the folder `dir` (refused with an InputError naming --record when it exists: a
  /// recording never writes into a folder it did not create) with images/, recording.json of
  /// `manifest` (not yet complete) and an empty exchanges.jsonl. Owns `inner`.
  RecordingCell(std::unique_ptr<BenchCell> inner, const std::string& dir,
                const RecordingManifest& manifest);
  ~RecordingCell() override;
  RecordingCell(const RecordingCell&) = delete;
  RecordingCell& operator=(const RecordingCell&) = delete;

  MoveResult MoveTo(int robot, const JointVector& q) override;
  JointVector ReadEncoders(int robot) override;
  cv::Mat GrabImage() override;
  cv::Mat GrabImageRegion(const cv::Rect& roi) override;
  MoveResult ExchangeTools() override;
  int CameraRobot() override;
  MoveResult JogTipToContact(int jogged_robot) override;
  MoveResult MountTarget(BracketTarget target) override;
  double ClockSeconds() override;
  double ReadTemperatureC(int robot) override;
  TrackerReading MeasureTracker(int robot) override;
  TwinTruth Truth() override;
  /// Recorded only when the cell set it (a cell without a simulated operator: no line).
  bool SetOperatorAlignmentError(double sigma_m) override;
  /// Rewrites recording.json as complete, with the number of exchanges and the end time.
  void Finish() override;

  /// Exchanges recorded so far.
  long exchanges() const { return seq_; }

 private:
  using Clock = std::chrono::steady_clock;
  /// Appends one line; `image` (PNG bytes, may be empty) goes into images/ beside it.
  void Append(const char* method, Clock::time_point t_call,
              const google::protobuf::Message& request,
              const google::protobuf::Message& response, const std::string& png = "");
  cv::Mat RecordImage(const cv::Mat& image, int x, int y, Clock::time_point t_call,
                      const cv::Rect* roi);

  std::string dir_;
  RecordingManifest manifest_;
  Clock::time_point t0_;
  int fd_ = -1;
  long seq_ = 0;
  std::mutex mutex_;
};

/// Protobuf's JSON of a message as a recording holds it: field names as in the .proto, fields
/// at their default value left out (the mapping's default), doubles printed so that they read
/// back to the same bits (a negative zero as -0.0: protobuf reads its own -0 as +0). Throws
/// std::runtime_error when protobuf cannot print it.
std::string RecordingJson(const google::protobuf::Message& message);

/// Now as ISO 8601 UTC ("2026-12-06T13:45:51Z").
std::string UtcNow();

}  // namespace twin
