#include "sim/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "sim/render/gl_context.h"

namespace twin {
namespace {

constexpr int kMinSceneGeoms = 1000;  // room for decor geoms on top of the model's

// mjr_makeContext reloads MuJoCo's global GL function pointers (DESIGN.md): contexts are
// created and destroyed one at a time.
std::mutex& ContextMutex() {
  static std::mutex mutex;
  return mutex;
}

struct ModelCopyDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};

// A private copy of `model` whose offscreen buffer is width x height with `msaa` samples, so the
// renderer's arguments, not the MJCF's <global offwidth/offheight> and <quality offsamples>,
// size the framebuffer (llvmpipe still clamps the samples to 4).
std::unique_ptr<mjModel, ModelCopyDeleter> SizedCopy(const mjModel* model, int width, int height,
                                                     int msaa) {
  std::unique_ptr<mjModel, ModelCopyDeleter> copy(mj_copyModel(nullptr, model));
  if (!copy) throw std::runtime_error("OffscreenRenderer: cannot copy the MuJoCo model");
  copy->vis.global.offwidth = width;
  copy->vis.global.offheight = height;
  copy->vis.quality.offsamples = msaa;
  return copy;
}

// The affine map x' = c + S (x - c), S = I + (factor - 1) a a^T: a scale by `factor` about the
// point c along the unit axis a.
struct AxisScale {
  double c[3], S[9];

  AxisScale(const double centre[3], const double axis[3], double factor) {
    for (int r = 0; r < 3; ++r) {
      c[r] = centre[r];
      for (int k = 0; k < 3; ++k) S[3 * r + k] = (r == k) + (factor - 1) * axis[r] * axis[k];
    }
  }
  void Point(float* p) const {
    const double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    for (int r = 0; r < 3; ++r) {
      p[r] = static_cast<float>(c[r] + S[3 * r] * d[0] + S[3 * r + 1] * d[1] + S[3 * r + 2] * d[2]);
    }
  }
  void Matrix(float* mat) const {  // row-major 3x3: mat' = S * mat
    float m[9];
    std::copy(mat, mat + 9, m);
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) {
        mat[3 * r + k] =
            static_cast<float>(S[3 * r] * m[k] + S[3 * r + 1] * m[3 + k] + S[3 * r + 2] * m[6 + k]);
      }
    }
  }
};

// Applies `scale` to the scene's geoms (position and orientation) and skin vertices.
void ScaleScene(mjvScene* scn, const AxisScale& scale) {
  for (int i = 0; i < scn->ngeom; ++i) {
    scale.Point(scn->geoms[i].pos);
    scale.Matrix(scn->geoms[i].mat);
  }
  for (int k = 0; k < scn->nskin; ++k) {
    for (int v = 0; v < scn->skinvertnum[k]; ++v) {
      scale.Point(scn->skinvert + 3 * (scn->skinvertadr[k] + v));
    }
  }
}

// Camera centre and right (image +x) axis of the mono view, from the two GL cameras.
void CameraCentreAndRight(const mjvScene& scn, double centre[3], double right[3]) {
  const mjvGLCamera& a = scn.camera[0];
  const mjvGLCamera& b = scn.camera[1];
  for (int i = 0; i < 3; ++i) centre[i] = 0.5 * (a.pos[i] + b.pos[i]);
  const float* f = a.forward;
  const float* u = a.up;
  right[0] = f[1] * u[2] - f[2] * u[1];  // right = forward x up
  right[1] = f[2] * u[0] - f[0] * u[2];
  right[2] = f[0] * u[1] - f[1] * u[0];
  const double n = std::sqrt(right[0] * right[0] + right[1] * right[1] + right[2] * right[2]);
  for (int i = 0; i < 3; ++i) right[i] /= n;
}

// glFrustum for OpenCV intrinsics. MuJoCo builds glFrustum(center -+ halfwidth, bottom, top,
// near, far) with halfwidth = 0.5 W/H (top - bottom), so the frustum fixes fy only; the x scale
// is fy too, and fx comes from scaling the scene along camera x by fx/fy. With window
// coordinates x_w = (near u - left) W / (right - left), pixel centres at x_w = i + 0.5, and
// OpenCV u_cv = x_w - 0.5 (v_cv = H - 0.5 - y_w after the row flip), matching
// u_cv = fx X/Z + cx, v_cv = fy Y/Z + cy (optical frame: y down, so y_eye = -Y) gives:
//   left = -n (cx + 0.5) / fy,  bottom = n (cy + 0.5 - H) / fy,  top = n (cy + 0.5) / fy.
void SetPinholeFrustum(mjvGLCamera* cam, const Intrinsics& K, double near_m, double far_m) {
  const double n = near_m;
  const double halfwidth = 0.5 * n * K.width / K.fy;
  cam->frustum_near = static_cast<float>(n);
  cam->frustum_far = static_cast<float>(far_m);
  cam->frustum_bottom = static_cast<float>(n * (K.cy + 0.5 - K.height) / K.fy);
  cam->frustum_top = static_cast<float>(n * (K.cy + 0.5) / K.fy);
  cam->frustum_center = static_cast<float>(-n * (K.cx + 0.5) / K.fy + halfwidth);
}

// The frustum of the pixels `roi` of the image of K: the full frustum's near-plane window
// (left = -n (cx + 0.5) / fy, top = n (cy + 0.5) / fy, n / fy per pixel) cut to roi's columns
// and rows. MuJoCo's halfwidth, 0.5 w / h (top - bottom) for the roi-sized viewport, is then
// 0.5 w n / fy: the same pixel size as the full frame.
void SetRegionFrustum(mjvGLCamera* cam, const Intrinsics& K, const cv::Rect& roi, double near_m,
                      double far_m) {
  const double pixel = near_m / K.fy;
  const double left = -near_m * (K.cx + 0.5) / K.fy + pixel * roi.x;
  const double top = near_m * (K.cy + 0.5) / K.fy - pixel * roi.y;
  cam->frustum_near = static_cast<float>(near_m);
  cam->frustum_far = static_cast<float>(far_m);
  cam->frustum_top = static_cast<float>(top);
  cam->frustum_bottom = static_cast<float>(top - pixel * roi.height);
  cam->frustum_center = static_cast<float>(left + 0.5 * pixel * roi.width);
}

}  // namespace

struct OffscreenRenderer::Impl {
  int width = 0, height = 0;
  std::unique_ptr<GlContext> gl;       // OSMesa or EGL (gl_context.h)
  std::vector<unsigned char> rgb;      // read-back buffer, bottom-up RGB
  mjvScene scene;
  mjrContext context;
  mjvOption option;
  double near_m = 0, far_m = 0;        // 0: the model's znear/zfar times extent
  bool made = false;                   // scene and context were made

  ~Impl() {
    if (!gl) return;
    std::lock_guard<std::mutex> lock(ContextMutex());
    if (made) {
      try {
        gl->MakeCurrent();
        mjr_freeContext(&context);  // GL objects: needs the context current
        gl->Release();
      } catch (const std::runtime_error&) {
        // Cannot be made current: destroying the context below frees its objects with it.
      }
      mjv_freeScene(&scene);
    }
    gl.reset();
  }

  // The context current on this thread for one call, released after it (gl_context.h: an EGL
  // context released is free for whichever thread calls next).
  class Bound {
   public:
    explicit Bound(Impl* r) : r_(r) {
      r_->gl->MakeCurrent();
      mjr_setBuffer(mjFB_OFFSCREEN, &r_->context);
    }
    ~Bound() { r_->gl->Release(); }
    Bound(const Bound&) = delete;
    Bound& operator=(const Bound&) = delete;

   private:
    Impl* r_;
  };

  // mjv_updateScene for camera `cam`, render and read back into `rgb`.
  void RenderToBuffer(const mjModel* m, mjData* d, mjvCamera* cam) {
    const Bound bound(this);
    mjv_updateScene(m, d, &option, nullptr, cam, mjCAT_ALL, &scene);
    RenderScene();
  }

  // Renders into the viewport (0, 0, w, h) of the framebuffer (default: all of it) and reads
  // it back into `rgb`.
  void RenderScene(int w = 0, int h = 0) {
    const mjrRect viewport = {0, 0, w > 0 ? w : width, h > 0 ? h : height};
    mjr_render(viewport, &scene, &context);
    mjr_readPixels(rgb.data(), nullptr, viewport, &context);
  }

  // The read-back buffer (w x h, default the framebuffer) as 8-bit BGR with OpenCV's
  // top-down rows.
  cv::Mat ToBgr(int w = 0, int h = 0) const {
    if (w <= 0 || h <= 0) {
      w = width;
      h = height;
    }
    const cv::Mat bottom_up(h, w, CV_8UC3, const_cast<unsigned char*>(rgb.data()));
    cv::Mat flipped, bgr;
    cv::flip(bottom_up, flipped, 0);
    cv::cvtColor(flipped, bgr, cv::COLOR_RGB2BGR);
    return bgr;
  }
};

OffscreenRenderer::OffscreenRenderer(const mjModel* model, int width, int height, int msaa)
    : impl_(new Impl) {
  if (width <= 0 || height <= 0 || msaa < 0) {
    throw std::invalid_argument("OffscreenRenderer: bad size " + std::to_string(width) + "x" +
                                std::to_string(height) + " or msaa " + std::to_string(msaa));
  }
  Impl& r = *impl_;
  r.width = width;
  r.height = height;
  r.rgb.resize(static_cast<size_t>(3) * width * height);
  mjv_defaultOption(&r.option);
  mjv_defaultScene(&r.scene);
  mjr_defaultContext(&r.context);
  std::lock_guard<std::mutex> lock(ContextMutex());
  r.gl = MakeGlContext(width, height);  // current on this thread
  const auto sized = SizedCopy(model, width, height, msaa);
  mjv_makeScene(model, &r.scene, std::max(kMinSceneGeoms, 2 * model->ngeom));
  mjr_makeContext(sized.get(), &r.context, mjFONTSCALE_100);
  r.made = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &r.context);
  if (r.context.currentBuffer != mjFB_OFFSCREEN) {
    throw std::runtime_error("OffscreenRenderer: no offscreen framebuffer");
  }
  r.gl->Release();  // each call makes it current again (Impl::Bound)
}

OffscreenRenderer::~OffscreenRenderer() = default;  // Impl frees the contexts

void OffscreenRenderer::SetClipPlanes(double near_m, double far_m) {
  if (!(near_m > 0 && far_m > near_m)) {
    throw std::invalid_argument("OffscreenRenderer: bad clip planes near " +
                                std::to_string(near_m) + " m, far " + std::to_string(far_m) +
                                " m");
  }
  impl_->near_m = near_m;
  impl_->far_m = far_m;
}

void OffscreenRenderer::SetSkybox(bool on) { impl_->scene.flags[mjRND_SKYBOX] = on ? 1 : 0; }

cv::Mat OffscreenRenderer::RenderPinhole(const mjModel* model, mjData* data, int camera_id,
                                         const Intrinsics& K) {
  Impl& r = *impl_;
  if (K.width != r.width || K.height != r.height) {
    throw std::invalid_argument("OffscreenRenderer: intrinsics are " + std::to_string(K.width) +
                                "x" + std::to_string(K.height) + ", renderer is " +
                                std::to_string(r.width) + "x" + std::to_string(r.height));
  }
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FIXED;
  cam.fixedcamid = camera_id;
  const Impl::Bound bound(&r);
  mjv_updateScene(model, data, &r.option, nullptr, &cam, mjCAT_ALL, &r.scene);
  // mjv_updateScene reset the frustum: replace it in both GL cameras (mono averages them).
  const double near_m = r.near_m > 0 ? r.near_m : r.scene.camera[0].frustum_near;
  const double far_m = r.far_m > 0 ? r.far_m : r.scene.camera[0].frustum_far;
  double centre[3], right[3];
  CameraCentreAndRight(r.scene, centre, right);
  for (int view = 0; view < 2; ++view) {
    SetPinholeFrustum(&r.scene.camera[view], K, near_m, far_m);
    for (int i = 0; i < 3; ++i) r.scene.camera[view].pos[i] = static_cast<float>(centre[i]);
  }
  if (K.fx != K.fy) ScaleScene(&r.scene, AxisScale(centre, right, K.fx / K.fy));
  r.RenderScene();
  return r.ToBgr();
}

cv::Mat OffscreenRenderer::RenderPinholeRegion(const mjModel* model, mjData* data, int camera_id,
                                               const Intrinsics& K, const cv::Rect& roi) {
  Impl& r = *impl_;
  if (K.width != r.width || K.height != r.height) {
    throw std::invalid_argument("OffscreenRenderer: intrinsics are " + std::to_string(K.width) +
                                "x" + std::to_string(K.height) + ", renderer is " +
                                std::to_string(r.width) + "x" + std::to_string(r.height));
  }
  if (roi.width < 1 || roi.height < 1 || roi.x < 0 || roi.y < 0 || roi.x + roi.width > r.width ||
      roi.y + roi.height > r.height) {
    throw std::invalid_argument("OffscreenRenderer: region " + std::to_string(roi.width) + "x" +
                                std::to_string(roi.height) + " at (" + std::to_string(roi.x) +
                                ", " + std::to_string(roi.y) + ") is not inside the " +
                                std::to_string(r.width) + "x" + std::to_string(r.height) +
                                " image");
  }
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FIXED;
  cam.fixedcamid = camera_id;
  const Impl::Bound bound(&r);
  mjv_updateScene(model, data, &r.option, nullptr, &cam, mjCAT_ALL, &r.scene);
  const double near_m = r.near_m > 0 ? r.near_m : r.scene.camera[0].frustum_near;
  const double far_m = r.far_m > 0 ? r.far_m : r.scene.camera[0].frustum_far;
  double centre[3], right[3];
  CameraCentreAndRight(r.scene, centre, right);
  for (int view = 0; view < 2; ++view) {
    SetRegionFrustum(&r.scene.camera[view], K, roi, near_m, far_m);
    for (int i = 0; i < 3; ++i) r.scene.camera[view].pos[i] = static_cast<float>(centre[i]);
  }
  if (K.fx != K.fy) ScaleScene(&r.scene, AxisScale(centre, right, K.fx / K.fy));
  r.RenderScene(roi.width, roi.height);
  return r.ToBgr(roi.width, roi.height);
}

cv::Mat OffscreenRenderer::RenderFree(const mjModel* model, mjData* data,
                                      const mjvCamera& camera) {
  mjvCamera cam = camera;  // mjv_updateScene may move a tracking camera's lookat
  impl_->RenderToBuffer(model, data, &cam);
  return impl_->ToBgr();
}

void OffscreenRenderer::RenderBare(const mjModel* model, mjData* data, int camera_id) {
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FIXED;
  cam.fixedcamid = camera_id;
  impl_->RenderToBuffer(model, data, &cam);
}

int OffscreenRenderer::width() const { return impl_->width; }
int OffscreenRenderer::height() const { return impl_->height; }

}  // namespace twin
