#include "remote/proto_convert.h"

#include <limits>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace twin::remote {

namespace {

[[noreturn]] void Bad(const std::string& what) { throw ProtocolError(what); }

void ToProto(const Vector3& v, bpb::Vector3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

Vector3 FromProto(const bpb::Vector3& v) { return Vector3(v.x(), v.y(), v.z()); }

void ToProto(const Transform& X, bpb::Transform* out) {
  out->clear_rotation();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out->add_rotation(X.linear()(r, c));
  }
  ToProto(Vector3(X.translation()), out->mutable_translation_m());
}

Transform FromProto(const bpb::Transform& X, const char* what) {
  if (X.rotation_size() != 9) {
    Bad(std::string(what) + ": a rotation has 9 numbers, got " +
        std::to_string(X.rotation_size()));
  }
  Transform out = Transform::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.linear()(r, c) = X.rotation(3 * r + c);
  }
  out.translation() = FromProto(X.translation_m());
  return out;
}

void ToProto(const KinematicModel& m, bpb::KinematicModel* out) {
  out->set_name(m.name);
  ToProto(m.X_BL0, out->mutable_base_to_dh0());
  ToProto(m.X_LtE, out->mutable_tool_to_end());
  for (const Link& l : m.links) {
    bpb::Link* p = out->add_links();
    p->set_name(l.name);
    p->set_joint_name(l.joint_name);
    bpb::DhParameters* dh = p->mutable_dh();
    dh->set_theta_offset_rad(l.dh.theta_offset);
    dh->set_d_m(l.dh.d);
    dh->set_a_m(l.dh.a);
    dh->set_alpha_rad(l.dh.alpha);
    dh->set_beta_rad(l.dh.beta);
    p->set_lower_rad(l.limits.lower);
    p->set_upper_rad(l.limits.upper);
    p->set_mass_kg(l.inertia.mass);
    ToProto(l.inertia.p_LiCom, p->mutable_com_m());
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) p->add_inertia_kg_m2(l.inertia.I_Com(r, c));
    }
  }
}

KinematicModel FromProto(const bpb::KinematicModel& m) {
  const int joints = m.links_size() - 1;
  if (joints < 1 || joints > kMaxJoints) {
    Bad("truth: a model has 2.." + std::to_string(kMaxJoints + 1) + " links, got " +
        std::to_string(m.links_size()));
  }
  KinematicModel out(joints);
  out.name = m.name();
  out.X_BL0 = FromProto(m.base_to_dh0(), "truth: model base_to_dh0");
  out.X_LtE = FromProto(m.tool_to_end(), "truth: model tool_to_end");
  for (int i = 0; i < m.links_size(); ++i) {
    const bpb::Link& p = m.links(i);
    Link& l = out.links[i];
    l.name = p.name();
    l.joint_name = p.joint_name();
    l.dh.theta_offset = p.dh().theta_offset_rad();
    l.dh.d = p.dh().d_m();
    l.dh.a = p.dh().a_m();
    l.dh.alpha = p.dh().alpha_rad();
    l.dh.beta = p.dh().beta_rad();
    l.limits.lower = p.lower_rad();
    l.limits.upper = p.upper_rad();
    l.inertia.mass = p.mass_kg();
    l.inertia.p_LiCom = FromProto(p.com_m());
    if (p.inertia_kg_m2_size() != 9) Bad("truth: a link's inertia has 9 numbers");
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) l.inertia.I_Com(r, c) = p.inertia_kg_m2(3 * r + c);
    }
  }
  return out;
}

void ToProto(const CameraSpec& c, bpb::CameraSpec* out) {
  out->set_robot(static_cast<uint32_t>(c.robot));
  ToProto(c.X_FC, out->mutable_flange_to_camera());
  out->set_width_px(static_cast<uint32_t>(c.intrinsics.width));
  out->set_height_px(static_cast<uint32_t>(c.intrinsics.height));
  out->set_fx_px(c.intrinsics.fx);
  out->set_fy_px(c.intrinsics.fy);
  out->set_cx_px(c.intrinsics.cx);
  out->set_cy_px(c.intrinsics.cy);
  out->set_k1(c.distortion.k1);
  out->set_k2(c.distortion.k2);
  out->set_p1(c.distortion.p1);
  out->set_p2(c.distortion.p2);
  out->set_k3(c.distortion.k3);
  out->set_msaa_samples(c.msaa_samples);
  out->set_near_m(c.near_m);
  out->set_far_m(c.far_m);
  out->set_skybox(c.skybox);
}

CameraSpec FromProto(const bpb::CameraSpec& c) {
  CameraSpec out;
  out.robot = static_cast<int>(c.robot());
  out.X_FC = FromProto(c.flange_to_camera(), "truth: camera flange_to_camera");
  out.intrinsics.width = static_cast<int>(c.width_px());
  out.intrinsics.height = static_cast<int>(c.height_px());
  out.intrinsics.fx = c.fx_px();
  out.intrinsics.fy = c.fy_px();
  out.intrinsics.cx = c.cx_px();
  out.intrinsics.cy = c.cy_px();
  out.distortion = Distortion{c.k1(), c.k2(), c.p1(), c.p2(), c.k3()};
  out.msaa_samples = c.msaa_samples();
  out.near_m = c.near_m();
  out.far_m = c.far_m();
  out.skybox = c.has_skybox() ? c.skybox() : true;
  return out;
}

void ToProto(const BoardSpec& b, bpb::BoardSpec* out) {
  out->set_robot(static_cast<uint32_t>(b.robot));
  out->set_squares_x(b.squares_x);
  out->set_squares_y(b.squares_y);
  out->set_square_m(b.square_m);
  out->set_margin_m(b.margin_m);
  out->set_thickness_m(b.thickness_m);
  out->set_mass_kg(b.mass_kg);
  ToProto(b.X_FT, out->mutable_flange_to_board());
}

BoardSpec FromProto(const bpb::BoardSpec& b) {
  BoardSpec out;
  out.robot = static_cast<int>(b.robot());
  out.squares_x = b.squares_x();
  out.squares_y = b.squares_y();
  out.square_m = b.square_m();
  out.margin_m = b.margin_m();
  out.thickness_m = b.thickness_m();
  out.mass_kg = b.mass_kg();
  out.X_FT = FromProto(b.flange_to_board(), "truth: board flange_to_board");
  return out;
}

void ToProto(const TrackerSpec& t, bpb::TrackerSpec* out) {
  out->set_present(t.present);
  out->set_robot(static_cast<uint32_t>(t.robot));
  ToProto(t.X_WT, out->mutable_world_to_tracker());
  ToProto(t.p_FR, out->mutable_reflector_in_flange_m());
  out->set_sigma_m(t.sigma_m);
  out->set_sigma_per_m(t.sigma_per_m);
  ToProto(t.drift_m_per_s, out->mutable_drift_m_per_s());
  out->set_max_range_m(t.max_range_m);
}

TrackerSpec FromProto(const bpb::TrackerSpec& t) {
  TrackerSpec out;
  out.present = t.present();
  out.robot = static_cast<int>(t.robot());
  out.X_WT = FromProto(t.world_to_tracker(), "truth: tracker world_to_tracker");
  out.p_FR = FromProto(t.reflector_in_flange_m());
  out.sigma_m = t.sigma_m();
  out.sigma_per_m = t.sigma_per_m();
  out.drift_m_per_s = FromProto(t.drift_m_per_s());
  out.max_range_m = t.max_range_m();
  return out;
}

// A per-robot field of the truth: exactly kMaxRobots entries (every slot crosses, used or not).
void CheckRobots(int n, const char* what) {
  if (n != kMaxRobots) {
    Bad(std::string("truth: ") + what + " has " + std::to_string(kMaxRobots) +
        " entries, got " + std::to_string(n));
  }
}

}  // namespace

pb::MoveStatus ToProto(MoveStatus status) {
  switch (status) {
    case MoveStatus::kSettled: return pb::MOVE_STATUS_SETTLED;
    case MoveStatus::kCollision: return pb::MOVE_STATUS_COLLISION;
    case MoveStatus::kNotSettled: return pb::MOVE_STATUS_NOT_SETTLED;
    case MoveStatus::kOutOfLimits: return pb::MOVE_STATUS_OUT_OF_LIMITS;
    case MoveStatus::kInvalidInput: return pb::MOVE_STATUS_INVALID_INPUT;
  }
  return pb::MOVE_STATUS_UNSPECIFIED;
}

MoveStatus FromProto(pb::MoveStatus status) {
  switch (status) {
    case pb::MOVE_STATUS_SETTLED: return MoveStatus::kSettled;
    case pb::MOVE_STATUS_COLLISION: return MoveStatus::kCollision;
    case pb::MOVE_STATUS_NOT_SETTLED: return MoveStatus::kNotSettled;
    case pb::MOVE_STATUS_OUT_OF_LIMITS: return MoveStatus::kOutOfLimits;
    case pb::MOVE_STATUS_INVALID_INPUT: return MoveStatus::kInvalidInput;
    case pb::MOVE_STATUS_STOPPED: return MoveStatus::kNotSettled;
    default: break;
  }
  Bad("a move result with status " + std::to_string(static_cast<int>(status)) +
      ", which protocol v1 does not define");
}

void ToProto(const MoveResult& result, pb::MoveResult* out) {
  out->set_status(ToProto(result.status));
  out->set_reason(result.reason);
  out->set_duration_s(result.duration_s);
}

MoveResult FromProto(const pb::MoveResult& result) {
  MoveResult out;
  out.status = FromProto(result.status());
  out.reason = result.reason();
  if (result.status() == pb::MOVE_STATUS_STOPPED) out.reason = "stopped: " + out.reason;
  out.duration_s = result.duration_s();
  return out;
}

pb::TrackerStatus ToProto(TrackerStatus status) {
  switch (status) {
    case TrackerStatus::kOk: return pb::TRACKER_STATUS_OK;
    case TrackerStatus::kNoTracker: return pb::TRACKER_STATUS_NO_TRACKER;
    case TrackerStatus::kOutOfRange: return pb::TRACKER_STATUS_OUT_OF_RANGE;
    case TrackerStatus::kOccluded: return pb::TRACKER_STATUS_OCCLUDED;
  }
  return pb::TRACKER_STATUS_UNSPECIFIED;
}

TrackerStatus FromProto(pb::TrackerStatus status) {
  switch (status) {
    case pb::TRACKER_STATUS_OK: return TrackerStatus::kOk;
    case pb::TRACKER_STATUS_NO_TRACKER: return TrackerStatus::kNoTracker;
    case pb::TRACKER_STATUS_OUT_OF_RANGE: return TrackerStatus::kOutOfRange;
    case pb::TRACKER_STATUS_OCCLUDED: return TrackerStatus::kOccluded;
    default: break;
  }
  Bad("a tracker reading with status " + std::to_string(static_cast<int>(status)) +
      ", which protocol v1 does not define");
}

void ToProto(const TrackerReading& reading, pb::MeasureTrackerResponse* out) {
  out->set_status(ToProto(reading.status));
  out->set_reason(reading.reason);
  out->set_x_m(reading.p_T.x());
  out->set_y_m(reading.p_T.y());
  out->set_z_m(reading.p_T.z());
  out->set_time_s(reading.time_s);
}

TrackerReading FromProto(const pb::MeasureTrackerResponse& reading) {
  TrackerReading out;
  out.status = FromProto(reading.status());
  out.reason = reading.reason();
  out.p_T = Vector3(reading.x_m(), reading.y_m(), reading.z_m());
  out.time_s = reading.time_s();
  return out;
}

pb::BracketTarget ToProto(BracketTarget target) {
  return target == BracketTarget::kIntrinsicsTarget ? pb::BRACKET_TARGET_INTRINSICS_TARGET
                                                    : pb::BRACKET_TARGET_FEATURE_BOARD;
}

BracketTarget FromProto(pb::BracketTarget target) {
  switch (target) {
    case pb::BRACKET_TARGET_FEATURE_BOARD: return BracketTarget::kFeatureBoard;
    case pb::BRACKET_TARGET_INTRINSICS_TARGET: return BracketTarget::kIntrinsicsTarget;
    default: break;
  }
  Bad("a bracket target " + std::to_string(static_cast<int>(target)) +
      ", which protocol v1 does not define");
}

JointVector JointsFromProto(const google::protobuf::RepeatedField<double>& q) {
  if (q.size() > kMaxJoints) {
    Bad(std::to_string(q.size()) + " joint angles; a robot has at most " +
        std::to_string(kMaxJoints));
  }
  JointVector out(q.size());
  for (int i = 0; i < q.size(); ++i) out(i) = q.Get(i);
  return out;
}

void JointsToProto(const JointVector& q, google::protobuf::RepeatedField<double>* out) {
  out->Clear();
  for (int i = 0; i < q.size(); ++i) out->Add(q(i));
}

void RegionToProto(const cv::Rect& roi, pb::PixelRegion* out) {
  out->set_x_px(roi.x);
  out->set_y_px(roi.y);
  out->set_width_px(roi.width);
  out->set_height_px(roi.height);
}

void EncodeImage(const cv::Mat& image, int x, int y, pb::GrabImageResponse* out,
                 const std::string& encoding) {
  const bool raw = encoding == "rgb8";
  out->set_encoding(raw ? "rgb8" : "png");
  out->set_x_px(x);
  out->set_y_px(y);
  out->set_width_px(static_cast<uint32_t>(image.cols));
  out->set_height_px(static_cast<uint32_t>(image.rows));
  out->clear_data();
  if (image.empty()) return;
  if (image.type() != CV_8UC3) Bad("an image to send must be 8-bit BGR");
  if (raw) {
    cv::Mat rgb;
    cv::cvtColor(image, rgb, cv::COLOR_BGR2RGB);  // continuous rows, no padding
    out->set_data(rgb.data, rgb.total() * rgb.elemSize());
    return;
  }
  // Level 1: PNG is lossless at every level; the lowest costs the least time per frame.
  std::vector<uchar> png;
  cv::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, 1});
  out->set_data(png.data(), png.size());
}

cv::Mat DecodeImage(const pb::GrabImageResponse& response) {
  if (response.data().empty()) return cv::Mat();
  if (response.encoding() == "rgb8") {
    const uint64_t w = response.width_px(), h = response.height_px();
    constexpr uint64_t kMaxSide = 1 << 20;  // no camera has a side of a million pixels
    if (w == 0 || h == 0 || w > kMaxSide || h > kMaxSide || response.data().size() != 3 * w * h) {
      Bad("an rgb8 image of " + std::to_string(response.data().size()) + " bytes whose response "
          "says " + std::to_string(w) + "x" + std::to_string(h) + " px");
    }
    const cv::Mat rgb(static_cast<int>(h), static_cast<int>(w), CV_8UC3,
                      const_cast<char*>(response.data().data()));
    cv::Mat bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    return bgr;
  }
  if (response.encoding() != "png") {
    Bad("an image encoded as '" + response.encoding() + "'; protocol v1 sends png or rgb8");
  }
  const std::vector<uchar> bytes(response.data().begin(), response.data().end());
  cv::Mat image = cv::imdecode(bytes, cv::IMREAD_COLOR);
  if (image.empty()) Bad("an image whose png data does not decode");
  if (static_cast<uint32_t>(image.cols) != response.width_px() ||
      static_cast<uint32_t>(image.rows) != response.height_px()) {
    Bad("an image of " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
        " px whose response says " + std::to_string(response.width_px()) + "x" +
        std::to_string(response.height_px()));
  }
  return image;
}

void ToProto(const TwinTruth& truth, bpb::TwinTruth* out) {
  out->Clear();
  out->set_num_robots(static_cast<uint32_t>(truth.num_robots));
  for (int r = 0; r < kMaxRobots; ++r) {
    ToProto(truth.models[r], out->add_models());
    out->add_length_scale(truth.length_scale[r]);
    ToProto(truth.X_WB[r], out->add_world_to_base());
    JointsToProto(truth.q_link[r], out->add_q_link()->mutable_q_rad());
    JointsToProto(truth.q_motor[r], out->add_q_motor()->mutable_q_rad());
    ToProto(truth.p_WTip[r], out->add_tip_in_world_m());
    ToProto(truth.X_WF[r], out->add_world_to_flange());
    ToProto(truth.X_FTip[r], out->add_flange_to_tip());
  }
  out->set_time_s(truth.time_s);
  ToProto(truth.X_WC, out->mutable_world_to_camera());
  ToProto(truth.X_WT, out->mutable_world_to_board());
  ToProto(truth.camera, out->mutable_camera());
  ToProto(truth.board, out->mutable_board());
  ToProto(truth.tracker, out->mutable_tracker());
}

TwinTruth FromProto(const bpb::TwinTruth& truth) {
  TwinTruth out;
  out.num_robots = static_cast<int>(truth.num_robots());
  if (out.num_robots < 1 || out.num_robots > kMaxRobots) Bad("truth: 1 or 2 robots");
  CheckRobots(truth.models_size(), "models");
  CheckRobots(truth.length_scale_size(), "length_scale");
  CheckRobots(truth.world_to_base_size(), "world_to_base");
  CheckRobots(truth.q_link_size(), "q_link");
  CheckRobots(truth.q_motor_size(), "q_motor");
  CheckRobots(truth.tip_in_world_m_size(), "tip_in_world_m");
  CheckRobots(truth.world_to_flange_size(), "world_to_flange");
  // flange_to_tip came later within v1: a truth without it (an older serve-cell or recording)
  // has its tips as NaN, so that what is scored with them is null, never silently wrong.
  const bool tips = truth.flange_to_tip_size() > 0;
  if (tips) CheckRobots(truth.flange_to_tip_size(), "flange_to_tip");
  for (int r = 0; r < kMaxRobots; ++r) {
    out.models[r] = FromProto(truth.models(r));
    out.length_scale[r] = truth.length_scale(r);
    out.X_WB[r] = FromProto(truth.world_to_base(r), "truth: world_to_base");
    out.q_link[r] = JointsFromProto(truth.q_link(r).q_rad());
    out.q_motor[r] = JointsFromProto(truth.q_motor(r).q_rad());
    out.p_WTip[r] = FromProto(truth.tip_in_world_m(r));
    out.X_WF[r] = FromProto(truth.world_to_flange(r), "truth: world_to_flange");
    if (tips) {
      out.X_FTip[r] = FromProto(truth.flange_to_tip(r), "truth: flange_to_tip");
    } else {
      out.X_FTip[r].translation().setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  out.time_s = truth.time_s();
  out.X_WC = FromProto(truth.world_to_camera(), "truth: world_to_camera");
  out.X_WT = FromProto(truth.world_to_board(), "truth: world_to_board");
  out.camera = FromProto(truth.camera());
  out.board = FromProto(truth.board());
  out.tracker = FromProto(truth.tracker());
  return out;
}

}  // namespace twin::remote
