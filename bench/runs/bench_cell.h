// The cell a run drives, wherever it is: the twin in this process, a cell served over the wire
// (`--cell grpc://HOST:PORT`, remote/), or a recorded session played back (`twinbench
// replay`). The procedure sees only its Cell interface; the bench reads the twin's truth
// through Truth(), after the procedure has ended, to score the estimates.
#pragma once

#include <memory>
#include <string>

#include "bench/report/recording_file.h"
#include "calib/cell/cell.h"
#include "sim/cell/twin_cell.h"

namespace twin {

class BenchCell : public Cell {
 public:
  /// The twin's truth now, for scoring after the procedure (bench only; never calib/).
  /// Throws InputError on a cell that has none to give (a real cell, `serve-cell --no-truth`).
  virtual TwinTruth Truth() = 0;
  /// The run has made its last call (the scoring included): a recording notes that it is
  /// complete, a replay checks that every recorded exchange was used (InputError if not).
  virtual void Finish() {}
  /// Whether Truth() can answer: false on a cell without truth (a real cell, `serve-cell
  /// --no-truth`), where a run scores nothing against truth. Asked after the procedure.
  virtual bool HasTruth() { return true; }
  /// Sets the twin's simulated operator: the standard deviation of the error with which the
  /// operator aligns the tips at each JogTipToContact [m] (TwinCell::SetOperatorAlignmentError;
  /// a handclasp stage's operator_error). Returns false on a cell whose operator is a person
  /// (a real cell, `serve-cell --no-truth`), where nothing is set.
  virtual bool SetOperatorAlignmentError(double /*sigma_m*/) { return false; }
};

/// A BenchCell that passes every call on to `inner` (subclasses override what they watch).
class ForwardingBenchCell : public BenchCell {
 public:
  explicit ForwardingBenchCell(BenchCell& inner) : inner_(inner) {}
  /// Owns `inner`.
  explicit ForwardingBenchCell(std::unique_ptr<BenchCell> inner)
      : owned_(std::move(inner)), inner_(*owned_) {}
  MoveResult MoveTo(int robot, const JointVector& q) override { return inner_.MoveTo(robot, q); }
  JointVector ReadEncoders(int robot) override { return inner_.ReadEncoders(robot); }
  cv::Mat GrabImage() override { return inner_.GrabImage(); }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override { return inner_.GrabImageRegion(roi); }
  MoveResult ExchangeTools() override { return inner_.ExchangeTools(); }
  int CameraRobot() override { return inner_.CameraRobot(); }
  MoveResult JogTipToContact(int jogged_robot) override {
    return inner_.JogTipToContact(jogged_robot);
  }
  MoveResult MountTarget(BracketTarget target) override { return inner_.MountTarget(target); }
  double ClockSeconds() override { return inner_.ClockSeconds(); }
  double ReadTemperatureC(int robot) override { return inner_.ReadTemperatureC(robot); }
  TrackerReading MeasureTracker(int robot) override { return inner_.MeasureTracker(robot); }
  TwinTruth Truth() override { return inner_.Truth(); }
  bool HasTruth() override { return inner_.HasTruth(); }
  bool SetOperatorAlignmentError(double sigma_m) override {
    return inner_.SetOperatorAlignmentError(sigma_m);
  }
  void Finish() override { inner_.Finish(); }

 protected:
  std::unique_ptr<BenchCell> owned_;  ///< null when the inner cell is someone else's
  BenchCell& inner_;
};

/// The twin of a scenario in this process: the TwinCell, as a BenchCell.
class LocalTwinCell : public BenchCell {
 public:
  explicit LocalTwinCell(TwinCell& twin) : twin_(twin) {}
  MoveResult MoveTo(int robot, const JointVector& q) override { return twin_.MoveTo(robot, q); }
  JointVector ReadEncoders(int robot) override { return twin_.ReadEncoders(robot); }
  cv::Mat GrabImage() override { return twin_.GrabImage(); }
  cv::Mat GrabImageRegion(const cv::Rect& roi) override { return twin_.GrabImageRegion(roi); }
  MoveResult ExchangeTools() override { return twin_.ExchangeTools(); }
  int CameraRobot() override { return twin_.CameraRobot(); }
  MoveResult JogTipToContact(int jogged_robot) override {
    return twin_.JogTipToContact(jogged_robot);
  }
  MoveResult MountTarget(BracketTarget target) override { return twin_.MountTarget(target); }
  double ClockSeconds() override { return twin_.ClockSeconds(); }
  double ReadTemperatureC(int robot) override { return twin_.ReadTemperatureC(robot); }
  TrackerReading MeasureTracker(int robot) override { return twin_.MeasureTracker(robot); }
  TwinTruth Truth() override { return twin_.Truth(); }
  bool SetOperatorAlignmentError(double sigma_m) override {
    twin_.SetOperatorAlignmentError(sigma_m);
    return true;
  }

 private:
  TwinCell& twin_;
};

/// Where a run's cell is (the run options `--cell` and `--record`).
struct CellOptions {
  /// Empty: the scenario's twin in this process. "grpc://HOST:PORT": a served cell.
  std::string address;
  /// TLS to a served cell: the CA certificate (PEM) that signed the server's certificate
  /// (empty: plaintext, which a server allows on loopback only).
  std::string tls_ca_file;
  /// A client certificate and its key (PEM), for a server that requires one.
  std::string tls_cert_file, tls_key_file;
  /// A file whose first line is the bearer token, for a server that requires one.
  std::string token_file;
  /// A folder to record every exchange into (empty: none); it must not exist yet.
  std::string record_dir;
  /// What recording.json says of the run (the scenario, trial, options); set by the run.
  RecordingManifest record_info;
  /// A recording to play back (`twinbench replay`; bench/runs/replay_cell.h) instead of a
  /// cell: every call must match the next recorded exchange.
  std::string replay_dir;
};

/// The cell a run drives: the scenario's twin here, the cell at options.address, or the
/// recording options.replay_dir played back; recorded into options.record_dir when one is
/// given. Throws InputError naming `where` for a bad
/// address, an unreachable cell or a record folder that exists.
std::unique_ptr<BenchCell> OpenBenchCell(const TwinSpec& twin, const std::string& where,
                                         const CellOptions& options);

}  // namespace twin
