// Where the board will be in the next frame, so that the cell grabs only that region
// (Cell::GrabImageRegion): the detector needs the board's squares and the white margin around
// them, nothing else. Pixels in OpenCV's convention; frame coordinates unless said otherwise.
#pragma once

#include <opencv2/core.hpp>

#include "calib/vision/feature_detector.h"

namespace twin {

/// The region to grab next: the bounding box of `det`'s inner corners (frame coordinates)
/// moved by `shift` [px] (the image motion the next move should cause), grown on each side by
/// `margin_squares` times the largest spacing between neighbouring corners (an inner corner
/// lies one square inside the board's edge, plus the printed margin) and by `slack_px` plus a
/// fifth of |shift| (the prediction's error), clipped to `image`. Empty for a detection that
/// was not found.
cv::Rect PredictBoardRegion(const FeatureDetection& det, const cv::Point2d& shift,
                            double margin_squares, double slack_px, const cv::Size& image);

/// Moves a detection made in an image of a region whose pixel (0, 0) is frame pixel `origin`
/// into frame coordinates (corners and feature point).
void ToFrameCoordinates(const cv::Point& origin, FeatureDetection* det);

}  // namespace twin
