// Off-screen rendering of a MuJoCo scene with OSMesa or EGL (gl_context.h: chosen once per
// process, TWINBENCH_GL), with exact pinhole intrinsics (fx, fy, cx, cy in OpenCV's pixel-centre
// convention). Several renderers may live in one process; each owns its GL context, makes it
// current for every call and releases it after, so successive calls may come from different
// threads (serve-cell's). Not thread-safe per instance: one call at a time.
#pragma once

#include <memory>

#include <mujoco/mujoco.h>
#include <opencv2/core.hpp>

#include "sim/world/twin_spec.h"

namespace twin {

class OffscreenRenderer {
 public:
  /// Creates a GL context (MakeGlContext) and MuJoCo render context for `model` with an offscreen
  /// framebuffer of width x height pixels and `msaa` samples; these override the model's
  /// <global offwidth/offheight> and <quality offsamples> (set on a private copy of the model).
  OffscreenRenderer(const mjModel* model, int width, int height, int msaa);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Near and far clipping distances [m] for RenderPinhole; until called, the model's
  /// <map znear/zfar> times its extent are used. Throws std::invalid_argument unless
  /// 0 < near < far.
  void SetClipPlanes(double near_m, double far_m);

  /// Draws the model's skybox behind the scene (the default) or not: the background is then
  /// black and every frame costs less (the sky is drawn over the whole viewport).
  void SetSkybox(bool on);

  /// Renders MJCF camera `camera_id` as an ideal pinhole with `K` (width/height of K must equal
  /// the renderer's). Returns 8-bit BGR in OpenCV row order.
  cv::Mat RenderPinhole(const mjModel* model, mjData* data, int camera_id, const Intrinsics& K);

  /// The pixels `roi` of RenderPinhole's image alone (roi inside K's image): the viewport is
  /// roi's size and the frustum the matching off-centre part of the full one (its near-plane
  /// window shifted by roi's offset in pixels), so each pixel is the full frame's pixel, up to
  /// the rasteriser's rounding at edges (renderer_test measures it). roi.width x roi.height BGR.
  /// Throws std::invalid_argument for a roi outside the image.
  cv::Mat RenderPinholeRegion(const mjModel* model, mjData* data, int camera_id,
                              const Intrinsics& K, const cv::Rect& roi);

  /// Renders a free (third-person) camera; returns 8-bit BGR in OpenCV row order.
  cv::Mat RenderFree(const mjModel* model, mjData* data, const mjvCamera& camera);

  /// The benchmark baseline: mjv_updateScene + mjr_render + mjr_readPixels of camera
  /// `camera_id`, nothing else (no intrinsics, no flip, no conversion).
  void RenderBare(const mjModel* model, mjData* data, int camera_id);

  int width() const;
  int height() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace twin
