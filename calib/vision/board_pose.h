// The board's pose from one image's detected corners, and a test of that pose against the
// corner noise: the feature point's position in the camera frame (its depth is the scale
// measurement of the optical-axis calibration, its offset across the axis what the servo left).
#pragma once

#include <optional>
#include <vector>

#include "calib/common/frames.h"
#include "calib/vision/feature_detector.h"
#include "calib/vision/intrinsics_calibration.h"

namespace twin {

/// The feature point P (the board frame's origin, its centre inner corner) in the camera frame.
struct BoardPose {
  Vector3 p_C = Vector3::Zero();        ///< P in the camera frame [m]
  /// Covariance of p_C [m^2]: sigma^2 (J^T J)^-1 of the reprojections' Jacobian in the pose,
  /// translation block, sigma the corner noise the intrinsics step measured (its RMS
  /// reprojection error). The intrinsics' own error (a common scale of every depth) is not in
  /// it: that is one error for the run, not noise.
  Matrix3 covariance = Matrix3::Zero();
  double reprojection_rms_px = 0.0;     ///< RMS of the refined pose's corner residuals [px]
  int corners = 0;                      ///< corners the pose was fitted to
  std::vector<cv::Point2d> reprojected;  ///< the corners as the pose reprojects them, in the
                                         ///< detection's order and coordinates [px]
};

/// solvePnP (IPPE, planar) on all inner corners with the known square length and the estimated
/// intrinsics and distortion, refined by Levenberg-Marquardt. The centre corner is the board's
/// centre of symmetry, so P does not depend on how OpenCV ordered the corners. nullopt when
/// the board was not found, the solver failed or the board lies behind the camera.
std::optional<BoardPose> EstimateBoardPose(const FeatureDetection& detection,
                                           const BoardGeometry& board,
                                           const IntrinsicsResult& intrinsics);

/// Chi-square test of a pose's corner residuals against the corner noise sigma [px]:
/// statistic = N rms^2 / sigma^2 on 2 N - 6 degrees of freedom (6 pose parameters).
struct BoardPoseTest {
  double statistic = 0.0;
  double dof = 0.0;
  double p_value = 1.0;  ///< upper tail; 1 when the test cannot be made (sigma 0, N <= 3)
};
BoardPoseTest TestBoardPose(const BoardPose& pose, double corner_sigma_px);

}  // namespace twin
