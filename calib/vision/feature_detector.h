// Detection of the chessboard's feature point P (the centre inner corner) in a camera image,
// the "corner detection algorithm" of the outer visual loop (Zhu et al. 2019, section V.A).
// OpenCV's findChessboardCorners + cornerSubPix, not the SB variant, which mislocks on a 4x4
// board (DESIGN.md, measured facts).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace twin {

/// The printed chessboard as the estimator knows it (what it printed), not the twin's truth.
struct BoardGeometry {
  int squares_x = 4;        ///< squares along the board's x axis (inner corners: squares_x - 1)
  int squares_y = 4;        ///< squares along y (inner corners: squares_y - 1)
  double square_m = 0.02;   ///< side of one square [m]
};

/// Throws InputError naming `where`, the field and the value: counts must be even and >= 2
/// (so a single centre inner corner exists) and square_m positive and finite.
void ValidateBoardGeometry(const BoardGeometry& board, const std::string& where);

enum class DetectionStatus {
  kFound,     ///< all inner corners found and refined
  kNotFound,  ///< no complete grid in the image (reason says why)
};

/// Name of a status for messages ("found", "not_found").
const char* ToString(DetectionStatus status);

/// Outcome of DetectFeaturePoint. Pixels in OpenCV's convention (pixel centres at integers).
struct FeatureDetection {
  DetectionStatus status = DetectionStatus::kNotFound;
  std::string reason;                 ///< why not found; empty when found
  std::vector<cv::Point2f> corners;   ///< all inner corners in OpenCV's detection order [px]
  cv::Size pattern_size;              ///< (columns, rows) of `corners` as OpenCV ordered them
  cv::Point2d feature_px;             ///< the centre inner corner P (u, v) [px]
};

/// Finds the board's inner corners in an 8-bit BGR (or grey) image and returns them with the
/// feature point pixel: the corner at the median row and median column of the detected grid,
/// which is the centre corner whatever order (flips, transposition) OpenCV reports. Throws
/// InputError for an empty image, an unsupported pixel type, or a bad board.
FeatureDetection DetectFeaturePoint(const cv::Mat& bgr, const BoardGeometry& board);

}  // namespace twin
