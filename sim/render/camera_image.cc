#include "sim/render/camera_image.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace twin {
namespace {

constexpr double kCanvasMargin = 2.0;     // [px] beyond the mapped points (bilinear support)
constexpr int kNewtonIterations = 30;     // converges in about 5 for lens-like distortion
constexpr double kNewtonTolerance = 1e-13;  // normalized units: about 1e-10 px

// OpenCV's Brown-Conrady model on normalized coordinates: (x, y) -> distorted (xd, yd), and
// the Jacobian J = d(xd, yd)/d(x, y), row-major.
void Distort(const Distortion& D, double x, double y, double* xd, double* yd, double J[4]) {
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (D.k1 + r2 * (D.k2 + r2 * D.k3));
  const double g = 2 * D.k1 + r2 * (4 * D.k2 + 6 * D.k3 * r2);  // d(radial)/d(r2) * 2
  *xd = x * radial + 2 * D.p1 * x * y + D.p2 * (r2 + 2 * x * x);
  *yd = y * radial + D.p1 * (r2 + 2 * y * y) + 2 * D.p2 * x * y;
  J[0] = radial + g * x * x + 2 * D.p1 * y + 6 * D.p2 * x;
  J[1] = g * x * y + 2 * D.p1 * x + 2 * D.p2 * y;
  J[2] = g * x * y + 2 * D.p1 * x + 2 * D.p2 * y;
  J[3] = radial + g * y * y + 6 * D.p1 * y + 2 * D.p2 * x;
}

// Inverts Distort by Newton's method from (xd, yd); false if it does not converge.
bool Undistort(const Distortion& D, double xd, double yd, double* x, double* y) {
  *x = xd;
  *y = yd;
  for (int it = 0; it < kNewtonIterations; ++it) {
    double fx, fy, J[4];
    Distort(D, *x, *y, &fx, &fy, J);
    const double ex = fx - xd, ey = fy - yd;
    if (std::abs(ex) < kNewtonTolerance && std::abs(ey) < kNewtonTolerance) return true;
    const double det = J[0] * J[3] - J[1] * J[2];
    if (!(std::abs(det) > 1e-12)) return false;
    *x -= (J[3] * ex - J[1] * ey) / det;
    *y -= (-J[2] * ex + J[0] * ey) / det;
  }
  return false;
}

std::string DistortionText(const Distortion& D) {
  return "(k1 " + std::to_string(D.k1) + ", k2 " + std::to_string(D.k2) + ", p1 " +
         std::to_string(D.p1) + ", p2 " + std::to_string(D.p2) + ", k3 " +
         std::to_string(D.k3) + ")";
}

}  // namespace

DistortionMapper::DistortionMapper(const Intrinsics& K, const Distortion& D) : canvas_(K) {
  if (!D.Any()) return;  // identity: the canvas is K's image
  map_x_.create(K.height, K.width, CV_32FC1);
  map_y_.create(K.height, K.width, CV_32FC1);
  // Ideal pixel (same fx, fy, cx, cy) seen by every distorted pixel, and their bounds.
  double min_x = 0, min_y = 0, max_x = K.width - 1, max_y = K.height - 1;
  for (int v = 0; v < K.height; ++v) {
    float* mx = map_x_.ptr<float>(v);
    float* my = map_y_.ptr<float>(v);
    for (int u = 0; u < K.width; ++u) {
      double x, y;
      if (!Undistort(D, (u - K.cx) / K.fx, (v - K.cy) / K.fy, &x, &y)) {
        throw std::invalid_argument("lens distortion " + DistortionText(D) +
                                    " cannot be inverted at pixel (" + std::to_string(u) + ", " +
                                    std::to_string(v) + ")");
      }
      const double px = K.fx * x + K.cx, py = K.fy * y + K.cy;
      min_x = std::min(min_x, px);
      max_x = std::max(max_x, px);
      min_y = std::min(min_y, py);
      max_y = std::max(max_y, py);
      mx[u] = static_cast<float>(px);
      my[u] = static_cast<float>(py);
    }
  }
  // Shift by whole pixels so every mapped point lies kCanvasMargin inside the canvas.
  const int ox = static_cast<int>(std::ceil(kCanvasMargin - min_x));
  const int oy = static_cast<int>(std::ceil(kCanvasMargin - min_y));
  canvas_.cx = K.cx + ox;
  canvas_.cy = K.cy + oy;
  canvas_.width = static_cast<int>(std::ceil(max_x + ox + kCanvasMargin)) + 1;
  canvas_.height = static_cast<int>(std::ceil(max_y + oy + kCanvasMargin)) + 1;
  map_x_ += ox;
  map_y_ += oy;
}

cv::Mat DistortionMapper::Apply(const cv::Mat& canvas_image) const {
  if (canvas_image.cols != canvas_.width || canvas_image.rows != canvas_.height) {
    throw std::invalid_argument(
        "DistortionMapper: canvas image is " + std::to_string(canvas_image.cols) + "x" +
        std::to_string(canvas_image.rows) + ", expected " + std::to_string(canvas_.width) + "x" +
        std::to_string(canvas_.height));
  }
  if (map_x_.empty()) return canvas_image.clone();
  cv::Mat distorted;
  cv::remap(canvas_image, distorted, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar::all(0));
  return distorted;
}

cv::Rect DistortionMapper::CanvasRegion(const cv::Rect& roi) const {
  if (map_x_.empty()) return roi;
  double min_x, max_x, min_y, max_y;
  cv::minMaxLoc(map_x_(roi), &min_x, &max_x);
  cv::minMaxLoc(map_y_(roi), &min_y, &max_y);
  // Bilinear sampling at x reads floor(x) and floor(x) + 1.
  const int x0 = static_cast<int>(std::floor(min_x)), y0 = static_cast<int>(std::floor(min_y));
  const int x1 = static_cast<int>(std::floor(max_x)) + 2, y1 = static_cast<int>(std::floor(max_y)) + 2;
  return cv::Rect(x0, y0, x1 - x0, y1 - y0) & cv::Rect(0, 0, canvas_.width, canvas_.height);
}

cv::Mat DistortionMapper::ApplyRegion(const cv::Mat& canvas_part, const cv::Rect& canvas_region,
                                      const cv::Rect& roi) const {
  if (canvas_part.cols != canvas_region.width || canvas_part.rows != canvas_region.height) {
    throw std::invalid_argument("DistortionMapper: canvas part is " +
                                std::to_string(canvas_part.cols) + "x" +
                                std::to_string(canvas_part.rows) + ", its region " +
                                std::to_string(canvas_region.width) + "x" +
                                std::to_string(canvas_region.height));
  }
  if (map_x_.empty()) return canvas_part.clone();
  // The maps of roi, in the coordinates of the canvas part (whole-pixel shifts: exact).
  const cv::Mat mx = map_x_(roi) - static_cast<float>(canvas_region.x);
  const cv::Mat my = map_y_(roi) - static_cast<float>(canvas_region.y);
  cv::Mat distorted;
  cv::remap(canvas_part, distorted, mx, my, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar::all(0));
  return distorted;
}

void AddImageNoise(cv::Mat* image, double sigma, std::uint64_t seed) {
  if (image == nullptr || image->empty() || sigma <= 0) return;
  // The pixels are whole numbers, so round(pixel + n) = pixel + round(n): the noise is drawn
  // already rounded, as 16-bit integers (one sample per channel of every pixel), and added
  // with saturation, which avoids two float conversions of the whole image.
  cv::Mat noise(image->size(), CV_MAKETYPE(CV_16S, image->channels()));
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::add(*image, noise, *image, cv::noArray(), image->type());
}

}  // namespace twin
