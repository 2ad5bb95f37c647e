// The OpenGL context an OffscreenRenderer draws in: OSMesa (software, always there) or EGL on a
// GPU, chosen once per process at run time.
//
// MuJoCo 2.2.2 finds its GL functions through whichever of eglGetProcAddress, then
// OSMesaGetProcAddress, then glXGetProcAddressARB the process can see, and reloads them in
// every mjr_makeContext. The program links OSMesa, never EGL: libEGL is opened with dlopen, and
// only into the global namespace once EGL is chosen. So one process renders with one back end,
// and the first renderer made fixes it.
//
// The choice: the environment variable TWINBENCH_GL (set by `twinbench --gl`), read when the
// first context is made:
//   auto    (the default) EGL on the first GPU that EGL enumerates; OSMesa where there is none
//           or EGL cannot make a context on it (the reason is kept for GlBackendDescription)
//   osmesa  OSMesa
//   egl     EGL on the first GPU, or on Mesa's software device where there is no GPU (to check
//           the EGL path on a machine without one); an error where EGL cannot make a context
//   egl:N   EGL on device N of eglQueryDevicesEXT
#pragma once

#include <memory>
#include <string>

namespace twin {

/// What TWINBENCH_GL asks for.
struct GlChoice {
  enum class Kind { kAuto, kOsmesa, kEgl };
  Kind kind = Kind::kAuto;
  int egl_device = -1;  // egl:N; -1: the first GPU, else the software device
};

/// Parses a TWINBENCH_GL value ("" is auto). Throws std::invalid_argument naming the value and
/// the accepted ones.
GlChoice ParseGlChoice(const std::string& text);

/// "TWINBENCH_GL=<its value>", where errors about the choice say they are.
std::string GlChoiceWhere();

/// ParseGlChoice of TWINBENCH_GL (unset: auto). Throws InputError (where: GlChoiceWhere()).
GlChoice GlChoiceFromEnvironment();

/// One OpenGL context of the process' back end, with no window: MuJoCo draws into its own
/// offscreen framebuffer. Not thread-safe. EGL binds a context to the thread it is current on
/// and refuses it to others meanwhile, so a user makes it current for a piece of work and
/// releases it after (OffscreenRenderer does, per call): then any thread may use it next.
class GlContext {
 public:
  virtual ~GlContext() = default;
  /// Makes the context current on the calling thread. Throws std::runtime_error when it cannot.
  virtual void MakeCurrent() = 0;
  /// Makes no context current on the calling thread, where this one is (OSMesa: nothing).
  virtual void Release() = 0;
};

/// A new context of the process' back end (chosen at the first call, from TWINBENCH_GL), with
/// a default framebuffer of width x height where the back end needs one. Throws InputError
/// (where: "TWINBENCH_GL=...") for a bad value or an `egl` that EGL cannot honour, and
/// std::runtime_error when no context can be made.
std::unique_ptr<GlContext> MakeGlContext(int width, int height);

/// The back end this process renders with, for logs and reports: "osmesa" or "egl", then
/// the GL_RENDERER string of the first context, and for auto's fall-back to OSMesa the reason,
/// e.g. "egl (NVIDIA H100 80GB HBM3/PCIe/SSE2)" or "osmesa (llvmpipe (LLVM 15.0.6, 256 bits);
/// EGL: no GPU device)". "none" before the first context.
std::string GlBackendDescription();

}  // namespace twin
