// Conversions between the Cell interface's types (calib/cell/cell.h) and the messages of the
// cell protocol (proto/twinbench/cell/v1/cell.proto), and between the twin's truth
// (sim/cell/twin_cell.h) and the bench's truth channel (proto/twinbench/bench/v1/truth.proto).
// Numbers cross unrounded (doubles stay doubles); images cross as PNG, which is lossless, so
// a run over the wire sees the same bits as an in-process run.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "calib/cell/cell.h"
#include "sim/cell/twin_cell.h"
#include "twinbench/bench/v1/truth.pb.h"
#include "twinbench/cell/v1/cell.pb.h"

namespace twin::remote {

namespace pb = ::twinbench::cell::v1;
namespace bpb = ::twinbench::bench::v1;

/// A message that cannot be turned back into the interface's types (a wrong count of numbers,
/// an image that does not decode, an unknown enum value): what and why.
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// --- move and tracker outcomes ----------------------------------------------------------------

pb::MoveStatus ToProto(MoveStatus status);
/// MOVE_STATUS_STOPPED becomes kNotSettled (the Cell interface has no stop: the procedure
/// sees a move that did not settle, with the reason); an unknown value throws ProtocolError.
MoveStatus FromProto(pb::MoveStatus status);
void ToProto(const MoveResult& result, pb::MoveResult* out);
MoveResult FromProto(const pb::MoveResult& result);

pb::TrackerStatus ToProto(TrackerStatus status);
TrackerStatus FromProto(pb::TrackerStatus status);
void ToProto(const TrackerReading& reading, pb::MeasureTrackerResponse* out);
TrackerReading FromProto(const pb::MeasureTrackerResponse& reading);

pb::BracketTarget ToProto(BracketTarget target);
BracketTarget FromProto(pb::BracketTarget target);

// --- joints and images ------------------------------------------------------------------------

/// The joint angles of a message; throws ProtocolError for more than kMaxJoints entries.
JointVector JointsFromProto(const google::protobuf::RepeatedField<double>& q);
void JointsToProto(const JointVector& q, google::protobuf::RepeatedField<double>* out);

/// A region of the frame as a request states it.
void RegionToProto(const cv::Rect& roi, pb::PixelRegion* out);

/// `image` (8-bit BGR, OpenCV row order; empty: a region that missed the frame) in `out`, its
/// pixel (0, 0) at frame column x, row y: as PNG, or with `encoding` "rgb8" as raw RGB rows.
void EncodeImage(const cv::Mat& image, int x, int y, pb::GrabImageResponse* out,
                 const std::string& encoding = "png");
/// The BGR image of a response (empty for empty data); throws ProtocolError when the data
/// does not decode as the encoding and size the response states.
cv::Mat DecodeImage(const pb::GrabImageResponse& response);

// --- the truth (bench only) -------------------------------------------------------------------

void ToProto(const TwinTruth& truth, bpb::TwinTruth* out);
/// Throws ProtocolError for a message of the wrong shape (counts of robots, links, numbers).
TwinTruth FromProto(const bpb::TwinTruth& truth);

}  // namespace twin::remote
