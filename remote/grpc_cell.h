// The client of the cell protocol (proto/twinbench/cell/v1/cell.proto): a Cell whose every call
// goes over gRPC to a served cell (`twinbench serve-cell`, or a hardware adapter). It holds a
// session for its lifetime and keeps it alive with heartbeats.
#pragma once

#include <memory>
#include <string>

#include "calib/cell/cell.h"
#include "remote/cell_channel.h"
#include "sim/cell/twin_cell.h"

namespace twin::remote {

/// Deadlines of the calls [s].
struct GrpcCellDeadlines {
  double call_s = 10.0;    ///< every call not named below
  double motion_s = 300.0; ///< MoveTo, JogTipToContact, ExchangeTools, MountTarget
  double image_s = 60.0;   ///< GrabImage
};

class GrpcCell : public Cell {
 public:
  /// Connects to `address` ("host:port"), calls Describe and OpenSession and starts the
  /// heartbeat. Throws InputError naming `where` (e.g. "--cell grpc://host:port") when the cell
  /// cannot be reached, refuses the credentials, or is held by another session.
  GrpcCell(const std::string& address, const GrpcCellCredentials& credentials,
           const std::string& where, GrpcCellDeadlines deadlines = {});
  /// Stops the heartbeat and closes the session (best effort).
  ~GrpcCell() override;
  GrpcCell(const GrpcCell&) = delete;
  GrpcCell& operator=(const GrpcCell&) = delete;

  // The Cell interface; a call the server refuses throws std::runtime_error naming the method
  // and the gRPC status.
  MoveResult MoveTo(int robot, const JointVector& q_target) override;
  JointVector ReadEncoders(int robot) override;
  cv::Mat GrabImage() override;
  /// Sends the region: the server renders or reads out only it.
  cv::Mat GrabImageRegion(const cv::Rect& roi) override;
  MoveResult ExchangeTools() override;
  int CameraRobot() override;
  MoveResult JogTipToContact(int jogged_robot) override;
  MoveResult MountTarget(BracketTarget target) override;
  double ClockSeconds() override;
  double ReadTemperatureC(int robot) override;
  TrackerReading MeasureTracker(int robot) override;

  /// The twin's truth over the bench's truth channel; InputError naming `where` when the cell
  /// offers none (a real cell, `serve-cell --no-truth`).
  TwinTruth Truth();
  /// Whether the cell offers the truth channel (asks it; false: UNIMPLEMENTED).
  bool HasTruth();
  /// Sets the served twin's simulated operator (the bench channel's SetOperatorError): the
  /// alignment error's standard deviation [m]. False when the cell has none (UNIMPLEMENTED: a
  /// real cell, `serve-cell --no-truth`); std::runtime_error when it refuses the value.
  bool SetOperatorAlignmentError(double sigma_m);
  /// The session id (tests).
  const std::string& session_id() const;
  /// The cell's name as Describe gave it.
  const std::string& cell_name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace twin::remote
