// `twinbench replay RDIR`: a BenchCell without a cell behind it that plays a recording
// (bench/report/recording_file.h, bench/runs/recording_cell.h) back. Each call must be the next
// recorded exchange, the same method with the same request exactly (doubles bit for bit); it
// answers the recorded response. Anything else means the replayed procedure diverged from the
// recorded one (other options, other code, another scenario): an InputError names the
// recording's file, the line (seq) and both calls.
#pragma once

#include <string>
#include <vector>

#include <google/protobuf/message.h>

#include "bench/report/recording_file.h"
#include "bench/runs/bench_cell.h"

namespace twin {

class ReplayCell : public BenchCell {
 public:
  /// Reads RDIR/recording.json (checked) and every line of RDIR/exchanges.jsonl; throws
  /// InputError naming the file (and line) for a missing or malformed recording.
  explicit ReplayCell(const std::string& dir);

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
  /// The live run had the truth: the recording holds a Truth exchange.
  bool HasTruth() override;
  /// True when the next exchange is a recorded SetOperatorError (which must match); false
  /// when the live run's cell had no simulated operator (nothing was recorded).
  bool SetOperatorAlignmentError(double sigma_m) override;
  /// Throws InputError ("the replay ended at seq N of M") unless every exchange was used.
  void Finish() override;

  const RecordingManifest& manifest() const { return manifest_; }
  /// Exchanges played back so far, and in the recording.
  long used() const { return static_cast<long>(next_); }
  long recorded() const { return static_cast<long>(exchanges_.size()); }

 private:
  /// Matches the next exchange against `method` and `request`; fills `response` from it.
  void Next(const char* method, const google::protobuf::Message& request,
            google::protobuf::Message* response);
  cv::Mat NextImage(const cv::Rect* roi);
  /// Why the recording ran out: partial, truncated, or a replay that asks more.
  std::string Truncation() const;

  std::string dir_, file_;
  RecordingManifest manifest_;
  std::vector<RecordedExchange> exchanges_;
  size_t next_ = 0;
};

/// The recording.json of the recording folder `dir`, checked (format, version).
RecordingManifest ReadRecordingManifest(const std::string& dir);

}  // namespace twin
