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

/// Throws PreconditionError naming `where`, the field and the value: counts must be even and
/// >= 2 (so a single centre inner corner exists) and square_m positive and finite. (A user's
/// board is checked where the scenario is read.)
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
  bool found_in_half_size = false;    ///< the adaptive search found it in the half-size copy
};

/// How DetectFeaturePoint searches; the corners are refined on the full image either way.
struct DetectorOptions {
  /// Where the global threshold finds no grid in an image of at least kCoarseSearchMinSide
  /// pixels on its shorter side, run the adaptive search on a half-size copy (cv::pyrDown)
  /// instead of the full image: a quarter of the pixels, and the full-size adaptive search
  /// costs 0.15-0.2 s on a 1024 x 768 frame. The price: a grid that only an adaptive threshold
  /// separates and whose squares are under ~26 px (13 px in the half-size copy, about what
  /// OpenCV needs) is not found. false: the adaptive search on the full image.
  bool coarse_search = true;
};

/// Shorter image side from which the adaptive fallback runs on the half-size copy [px]; below
/// it the full-size search is cheap.
constexpr int kCoarseSearchMinSide = 300;

/// Finds the board's inner corners in an 8-bit BGR (or grey) image and returns them with the
/// feature point pixel: the corner at the median row and median column of the detected grid,
/// which is the centre corner whatever order (flips, transposition) OpenCV reports. Throws
/// PreconditionError for an empty image, an unsupported pixel type, or a bad board.
FeatureDetection DetectFeaturePoint(const cv::Mat& bgr, const BoardGeometry& board,
                                    const DetectorOptions& options = DetectorOptions());

}  // namespace twin
