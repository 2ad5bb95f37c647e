#include "calib/vision/board_pose.h"

#include <cmath>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "calib/diagnosis/statistics.h"

namespace twin {

std::optional<BoardPose> EstimateBoardPose(const FeatureDetection& det, const BoardGeometry& board,
                                           const IntrinsicsResult& intr) {
  if (det.status != DetectionStatus::kFound) return std::nullopt;
  const cv::Size n = det.pattern_size;
  if (n.width * n.height != static_cast<int>(det.corners.size()) || det.corners.size() < 4) {
    return std::nullopt;
  }
  std::vector<cv::Point3d> object;
  for (int r = 0; r < n.height; ++r) {
    for (int c = 0; c < n.width; ++c) {
      object.emplace_back((c - n.width / 2) * board.square_m, (r - n.height / 2) * board.square_m,
                          0.0);
    }
  }
  std::vector<cv::Point2d> pixels(det.corners.begin(), det.corners.end());
  const PinholeIntrinsics& k = intr.intrinsics;
  const DistortionCoefficients& d = intr.distortion;
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const cv::Vec<double, 5> dist(d.k1, d.k2, d.p1, d.p2, d.k3);
  cv::Vec3d rvec, tvec;
  if (!cv::solvePnP(object, pixels, K, dist, rvec, tvec, false, cv::SOLVEPNP_IPPE)) {
    return std::nullopt;
  }
  cv::solvePnPRefineLM(object, pixels, K, dist, rvec, tvec);
  if (!(tvec[2] > 0)) return std::nullopt;
  BoardPose f;
  f.p_C = Vector3(tvec[0], tvec[1], tvec[2]);
  std::vector<cv::Point2d> projected;
  cv::Mat jacobian;  // 2N x (3 rvec + 3 tvec + 2 f + 2 c + 5 distortion)
  cv::projectPoints(object, rvec, tvec, K, dist, projected, jacobian);
  double sum_sq = 0.0;
  for (size_t i = 0; i < projected.size(); ++i) {
    const cv::Point2d e = projected[i] - pixels[i];
    sum_sq += e.dot(e);
  }
  f.corners = static_cast<int>(projected.size());
  f.reprojected = projected;
  f.reprojection_rms_px = std::sqrt(sum_sq / static_cast<double>(projected.size()));
  Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
  for (int row = 0; row < jacobian.rows; ++row) {
    Eigen::Matrix<double, 6, 1> g;
    for (int c = 0; c < 6; ++c) g(c) = jacobian.at<double>(row, c);
    JtJ += g * g.transpose();
  }
  const Eigen::Matrix<double, 6, 6> cov = intr.rms_px * intr.rms_px * JtJ.inverse();
  if (cov.allFinite()) f.covariance = cov.block<3, 3>(3, 3);
  return f;
}

BoardPoseTest TestBoardPose(const BoardPose& pose, double corner_sigma_px) {
  BoardPoseTest t;
  t.dof = 2.0 * pose.corners - 6.0;
  if (!(corner_sigma_px > 0) || t.dof < 1) return t;
  t.statistic = pose.corners * pose.reprojection_rms_px * pose.reprojection_rms_px /
                (corner_sigma_px * corner_sigma_px);
  t.p_value = stats::ChiSquareUpperTail(t.statistic, t.dof);
  return t;
}

}  // namespace twin
