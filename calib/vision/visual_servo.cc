#include "calib/vision/visual_servo.h"

#include <cmath>
#include <sstream>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "calib/cell/cell_moves.h"
#include "calib/vision/board_region.h"
#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "calib/model/measurement_context.h"

namespace twin {
namespace {

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Depth z_f of P along the optical axis [m], from the board pose by solvePnP (planar IPPE).
// The object grid follows OpenCV's detection order, so it needs no knowledge of that order:
// the centre corner is P in either case. Returns a non-positive value when it fails.
double DepthFromPnp(const FeatureDetection& det, const BoardGeometry& board,
                    const PinholeIntrinsics& k) {
  const cv::Size n = det.pattern_size;
  std::vector<cv::Point3f> object;
  object.reserve(det.corners.size());
  for (int r = 0; r < n.height; ++r) {
    for (int c = 0; c < n.width; ++c) {
      object.emplace_back(static_cast<float>(c * board.square_m),
                          static_cast<float>(r * board.square_m), 0.0f);
    }
  }
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  cv::Vec3d rvec, tvec;
  if (!cv::solvePnP(object, det.corners, K, cv::noArray(), rvec, tvec, false,
                    cv::SOLVEPNP_IPPE)) {
    return -1.0;
  }
  cv::Matx33d R;
  cv::Rodrigues(rvec, R);
  const cv::Vec3d p_centre((n.width / 2) * board.square_m, (n.height / 2) * board.square_m, 0);
  const cv::Vec3d p_C = R * p_centre + tvec;
  return p_C[2];
}

// Moves shorter than this do not teach the step model: the image noise of the two detections
// (about 0.03 px each) would be more than 2 % of the motion, the size of what it learns.
constexpr double kMinLearningStepPx = 2.0;
// The identity prior of the step model weighs as much as a 2 px move in each direction: the
// first long moves (tens of pixels at the first position of an axis) outweigh it at once.
constexpr double kStepModelPriorPx = 2.0;

}  // namespace

Eigen::Matrix2d ServoStepModel::Matrix(double prior_px) const {
  const double w = prior_px * prior_px;
  const Eigen::Matrix2d A = sum_oc + w * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d B = sum_cc + w * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d M = A * B.inverse();
  // A model far from the identity is a wrong model (a move that collided, a mislocked board):
  // the rough rotations are off by degrees, not tens of degrees.
  if (!M.allFinite() || (M - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff() > 0.3) {
    return Eigen::Matrix2d::Identity();
  }
  return M;
}

void ServoStepModel::Add(const Eigen::Vector2d& c, const Eigen::Vector2d& observed) {
  sum_oc += observed * c.transpose();
  sum_cc += c * c.transpose();
  ++pairs;
}

void ValidateServoOptions(const ServoOptions& o) {
  // The scenario's calibration.servo keys are bounded where they are read
  // (bench/io/calibration_config.cc) and no user sets the others: a bad value is our bug,
  // except the gain, whose scenario bound (0.01 to 2) admits 2.
  TWIN_REQUIRE(std::isfinite(o.tolerance_px) && o.tolerance_px > 0,
               "tolerance_px = " + Num(o.tolerance_px) + ": expected > 0 [px]");
  TWIN_REQUIRE(o.max_iterations >= 0,
               "max_iterations = " + std::to_string(o.max_iterations) + ": expected >= 0");
  if (!std::isfinite(o.gain) || o.gain <= 0 || o.gain >= 2) {
    throw InputError("ServoOptions.gain", "gain = " + Num(o.gain) +
                                              ": expected in (0, 2) (calibration.servo.gain)");
  }
  TWIN_REQUIRE(std::isfinite(o.nominal_depth_m) && o.nominal_depth_m >= 0,
               "nominal_depth_m = " + Num(o.nominal_depth_m) +
                   ": expected >= 0 [m] (0: estimate by solvePnP)");
  TWIN_REQUIRE(std::isfinite(o.max_step_m) && o.max_step_m > 0,
               "max_step_m = " + Num(o.max_step_m) + ": expected > 0 [m]");
  TWIN_REQUIRE(o.encoder_readings >= 1,
               "encoder_readings = " + std::to_string(o.encoder_readings) + ": expected >= 1");
}

const char* ToString(ServoStatus status) {
  switch (status) {
    case ServoStatus::kAligned: return "aligned";
    case ServoStatus::kBoardNotFound: return "board_not_found";
    case ServoStatus::kIkFailed: return "ik_failed";
    case ServoStatus::kMoveFailed: return "move_failed";
    case ServoStatus::kJointLimits: return "joint_limits";
    case ServoStatus::kNotConverged: return "not_converged";
  }
  return "unknown";
}

ServoResult AlignFeatureToOpticalAxis(Cell& cell, const ServoSetup& setup,
                                      const JointVector& q_passive_start,
                                      const ServoOptions& options,
                                      const cv::Rect& first_region,
                                      ServoStepModel* step_model) {
  ValidateServoOptions(options);
  ValidateBoardGeometry(setup.board, "ServoSetup.board");
  TWIN_REQUIRE(setup.passive_robot == 0 || setup.passive_robot == 1,
               "passive_robot = " + std::to_string(setup.passive_robot) + ": expected 0 or 1");
  // The intrinsics are a successful calibration's (the procedure stops at a failed one).
  const PinholeIntrinsics& k = setup.intrinsics;
  TWIN_REQUIRE(k.fx > 0 && k.fy > 0 && std::isfinite(k.cx) && std::isfinite(k.cy),
               "fx = " + Num(k.fx) + ", fy = " + Num(k.fy) + ", cx = " + Num(k.cx) +
                   ", cy = " + Num(k.cy) + ": expected positive focal lengths, finite centre");
  const int passive = setup.passive_robot;
  ServoResult result;
  auto finish = [&](ServoStatus status, const std::string& reason) {
    result.status = status;
    result.reason = reason;
    // The arm is at rest: the mean of several readings (summed, then divided once).
    JointVector sum = cell.ReadEncoders(passive);
    for (int i = 1; i < options.encoder_readings; ++i) sum += cell.ReadEncoders(passive);
    result.q_passive = sum / static_cast<double>(options.encoder_readings);
    return result;
  };

  if (!WithinLimits(setup.passive_model, q_passive_start)) {
    return finish(ServoStatus::kJointLimits,
                  "start pose of robot " + std::to_string(passive) + " is outside its limits");
  }
  result.approach = JointVector::Zero(q_passive_start.size());
  // Each joint's last motion over the corrections: the sign of each commanded target against
  // the one before (the start pose first), as the motors moved; a correction of a few
  // microradians is not to be told from the encoders' noise, so readings would not do. The
  // start move's own direction is not known here (where the robot came from is the caller's).
  const auto record_approach = [&](const JointVector& before, const JointVector& target) {
    const JointVector a = ApproachDirections(before, target);
    for (int i = 0; i < a.size() && i < result.approach.size(); ++i) {
      if (a(i) != 0.0) result.approach(i) = a(i);
    }
  };
  const MoveResult start = MoveAvoidingSweep(cell, passive, q_passive_start);
  JointVector last_target = q_passive_start;
  if (start.status != MoveStatus::kSettled) {
    return finish(start.status == MoveStatus::kOutOfLimits ? ServoStatus::kJointLimits
                                                           : ServoStatus::kMoveFailed,
                  std::string("move to the start pose: ") + ToString(start.status) + ": " +
                      start.reason);
  }

  // Eq. 43, read right to left: camera C -> active flange F -> active base Ba -> passive base
  // Bp, i.e. R_BpC = R_BpBa R_BaF R_FC with R_BpBa = R_BaBp^T and R_BaF from the nominal FK at
  // the active encoder reading.
  const Matrix3 R_BaF =
      ForwardKinematics(setup.active_model, setup.q_active).flange().linear();
  const Matrix3 R_BpC = setup.R_BaBp.transpose() * R_BaF * setup.R_FC;

  IkOptions ik_options;
  ik_options.seed = options.ik_seed;
  cv::Rect region = options.use_regions ? first_region : cv::Rect();
  Eigen::Vector2d last_command = Eigen::Vector2d::Zero(), last_error = Eigen::Vector2d::Zero();
  bool have_command = false;
  cv::Size frame_size(0, 0);  // known after the first whole frame
  for (int iteration = 0;; ++iteration) {
    // A region where the board is expected, else (or when it is not found there) a frame.
    cv::Mat image;
    cv::Point origin(0, 0);
    FeatureDetection det;
    if (!region.empty()) {
      image = cell.GrabImageRegion(region);
      ++result.frames;
      ++result.region_frames;
      origin = region.tl();
      if (!image.empty()) det = DetectFeaturePoint(image, setup.board);
      if (det.status != DetectionStatus::kFound) ++result.full_frame_fallbacks;
    }
    if (det.status != DetectionStatus::kFound) {
      image = cell.GrabImage();
      ++result.frames;
      origin = cv::Point(0, 0);
      frame_size = image.size();
      det = DetectFeaturePoint(image, setup.board);
    }
    if (result.image_before.empty()) {
      result.image_before = image.clone();
      result.image_before_origin = origin;
    }
    result.image_after = image;
    result.image_after_origin = origin;
    ToFrameCoordinates(origin, &det);
    result.detection_after = det;
    if (det.status != DetectionStatus::kFound) {
      return finish(ServoStatus::kBoardNotFound,
                    "frame " + std::to_string(result.frames) + ": " + det.reason);
    }
    // Eq. 31: pixel deviation of P from the principal point.
    const double du = det.feature_px.x - k.cx;
    const double dv = det.feature_px.y - k.cy;
    result.pixel_error = cv::Point2d(du, dv);
    if (result.moves == 0) {  // the first detection of this pose
      result.first_pixel_error = result.pixel_error;
    }
    if (step_model && have_command) {
      // What the last move did to the image, against what it commanded.
      const Eigen::Vector2d observed(du - last_error.x(), dv - last_error.y());
      if (last_command.norm() >= kMinLearningStepPx) step_model->Add(last_command, observed);
    }
    if (std::abs(du) < options.tolerance_px && std::abs(dv) < options.tolerance_px) {
      return finish(ServoStatus::kAligned, "");
    }
    if (iteration >= options.max_iterations) {
      return finish(ServoStatus::kNotConverged,
                    "pixel error (" + Num(du) + ", " + Num(dv) + ") px after " +
                        std::to_string(result.moves) + " moves (max_iterations = " +
                        std::to_string(options.max_iterations) + ")");
    }

    double z = options.nominal_depth_m;
    if (z <= 0) {
      z = DepthFromPnp(det, setup.board, k);
      if (!(z > 0) || !std::isfinite(z)) {
        return finish(ServoStatus::kBoardNotFound,
                      "frame " + std::to_string(result.frames) +
                          ": solvePnP gave no board pose in front of the camera");
      }
    }
    // Eq. 42: offset of P from the axis in C (x right, y down), then in Bp. P must move by
    // minus that offset to reach the axis: the wanted image motion is -gain (du, dv), and the
    // command that achieves it by the learnt step model M^-1 of that.
    Eigen::Vector2d command = -options.gain * Eigen::Vector2d(du, dv);
    if (step_model) command = step_model->Matrix(kStepModelPriorPx).inverse() * command;
    Vector3 step_Bp = R_BpC * Vector3(command.x() * z / k.fx, command.y() * z / k.fy, 0.0);
    // A correction longer than max_step_m is taken in moves of that length, each followed by
    // a new image (a far start: a rough base transform, a large kinematic error); the image
    // motion wanted from this move shrinks with it.
    double step_fraction = 1.0;
    if (step_Bp.norm() > options.max_step_m) {
      step_fraction = options.max_step_m / step_Bp.norm();
      step_Bp *= step_fraction;
      command *= step_fraction;
      ++result.limited_moves;
    }

    const JointVector q_now = cell.ReadEncoders(passive);
    Transform X_BpE_target = EndPose(setup.passive_model, q_now);
    X_BpE_target.translation() += step_Bp;
    const IkResult ik = SolveIk(setup.passive_model, X_BpE_target, q_now, ik_options);
    if (ik.status == IkStatus::kJointLimits) {
      return finish(ServoStatus::kJointLimits, "nominal IK: " + ik.reason);
    }
    if (ik.status != IkStatus::kSuccess) {
      return finish(ServoStatus::kIkFailed,
                    std::string("nominal IK: ") + ToString(ik.status) + ": " + ik.reason);
    }
    if (!WithinLimits(setup.passive_model, ik.q)) {
      return finish(ServoStatus::kJointLimits, "IK solution outside the joint limits");
    }
    const MoveResult move = cell.MoveTo(passive, ik.q);
    ++result.moves;
    record_approach(last_target, ik.q);
    last_target = ik.q;
    last_command = command;
    last_error = Eigen::Vector2d(du, dv);
    have_command = true;
    if (options.use_regions) {
      // The move should bring P onto the principal point: the board moves by -gain (du, dv).
      // Before a whole frame was seen the cell clips the region to its image.
      if (frame_size.width == 0) frame_size = cv::Size(1 << 20, 1 << 20);
      region = PredictBoardRegion(det, -options.gain * step_fraction * cv::Point2d(du, dv),
                                  options.region_margin_squares, options.region_slack_px,
                                  frame_size);
    }
    if (move.status != MoveStatus::kSettled) {
      return finish(move.status == MoveStatus::kOutOfLimits ? ServoStatus::kJointLimits
                                                            : ServoStatus::kMoveFailed,
                    "move " + std::to_string(result.moves) + ": " + ToString(move.status) +
                        ": " + move.reason);
    }
  }
}

}  // namespace twin
