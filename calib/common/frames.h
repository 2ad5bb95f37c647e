// Frame and unit conventions used everywhere in the project (DESIGN.md, convention 1).
//
// Monogram notation, as in Drake:
//   X_AB  rigid transform (Eigen::Isometry3d): pose of frame B measured in frame A,
//         so p_AQ = X_AB * p_BQ.
//   R_AB  rotation of frame B in frame A.
//   p_AQ  position of point Q measured and expressed in frame A.
//   w_A   a small rotation (rotation vector) expressed in frame A.
// Frame letters:
//   W world, B1/B2 robot bases, L0..L7 the improved-DH link frames of one arm (L0 is the DH
//   base frame, L6 the flange, L7 the tool link: chessboard feature point or camera mount),
//   F1/F2 flanges, C camera (OpenCV optical frame: +z along the optical axis, +x right,
//   +y down in the image), T target (chessboard), P feature point, E end frame of a chain.
// Units: SI inside the code (metres, radians, kilograms). Millimetres and degrees appear only
// in reports and in model files that declare them, as the papers use them.
#pragma once

#include <Eigen/Geometry>

namespace twin {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Transform = Eigen::Isometry3d;

constexpr double kPi = 3.14159265358979323846;
inline constexpr double DegToRad(double deg) { return deg * kPi / 180.0; }
inline constexpr double RadToDeg(double rad) { return rad * 180.0 / kPi; }

/// The cross-product matrix [v]x: [v]x u = v x u.
inline Matrix3 SkewMatrix(const Vector3& v) {
  Matrix3 s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

}  // namespace twin
