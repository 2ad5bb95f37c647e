// Turning ideal pinhole renders into camera images: Brown-Conrady distortion by remapping an
// ideal image rendered on a larger canvas (DESIGN.md), and image noise. OpenCV only.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

#include "sim/world/twin_spec.h"

namespace twin {

/// Maps from an ideal pinhole canvas to the distorted image of a camera.
class DistortionMapper {
 public:
  /// Plans the canvas: an ideal pinhole image (same fx, fy) large enough to cover every pixel
  /// of the distorted width x height image, and the remap tables.
  DistortionMapper(const Intrinsics& K, const Distortion& D);
  /// Intrinsics of the ideal canvas to render (larger than K's image when distorted).
  const Intrinsics& canvas() const { return canvas_; }
  /// The distorted image from an ideal canvas render (bilinear remap).
  cv::Mat Apply(const cv::Mat& canvas_image) const;
  /// The canvas rectangle whose pixels the distorted pixels `roi` (inside the image) sample:
  /// the bounding box of their map entries with the bilinear neighbours, inside the canvas.
  /// Without distortion, roi itself.
  cv::Rect CanvasRegion(const cv::Rect& roi) const;
  /// The distorted pixels `roi` from the canvas pixels `canvas_region` (CanvasRegion(roi),
  /// rendered by region): equal to Apply's pixels there.
  cv::Mat ApplyRegion(const cv::Mat& canvas_part, const cv::Rect& canvas_region,
                      const cv::Rect& roi) const;
  /// Remap tables (CV_32FC1, distorted image size): the canvas x / y [px] that each distorted
  /// pixel samples (empty without distortion, where Apply returns a copy of its input).
  const cv::Mat& map_x() const { return map_x_; }
  const cv::Mat& map_y() const { return map_y_; }

 private:
  Intrinsics canvas_;
  cv::Mat map_x_, map_y_;
};

/// Adds zero-mean Gaussian noise of `sigma` grey levels to every channel, saturating.
void AddImageNoise(cv::Mat* image, double sigma, std::uint64_t seed);

}  // namespace twin
