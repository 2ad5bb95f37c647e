#include "sim/render/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/osmesa.h>
#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "calib/common/errors.h"

namespace twin {
namespace {

constexpr const char* kEglLibrary = "libEGL.so.1";  // libglvnd's, Debian's libegl1

std::string EglErrorText(EGLint code) {
  char hex[16];
  std::snprintf(hex, sizeof(hex), "0x%04X", static_cast<unsigned>(code));
  return hex;
}

// EGL's entry points, from a dlopen'ed libEGL (never linked: see the header).
struct EglApi {
  void* library = nullptr;
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLTERMINATEPROC Terminate = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLGETCURRENTCONTEXTPROC GetCurrentContext = nullptr;
  PFNEGLQUERYDEVICESEXTPROC QueryDevices = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceString = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplay = nullptr;

  // Opens libEGL privately (RTLD_LOCAL: MuJoCo cannot see it yet). Returns "" or why not.
  std::string Open() {
    library = dlopen(kEglLibrary, RTLD_NOW | RTLD_LOCAL);
    if (!library) return std::string("cannot open ") + kEglLibrary;
    // Each pointer from dlsym, its type from the member it is stored in.
    bool all = true;
    const auto load = [&](auto* fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(dlsym(library, name));
      all = all && *fn != nullptr;
    };
    load(&GetProcAddress, "eglGetProcAddress");
    load(&GetError, "eglGetError");
    load(&Initialize, "eglInitialize");
    load(&Terminate, "eglTerminate");
    load(&BindAPI, "eglBindAPI");
    load(&ChooseConfig, "eglChooseConfig");
    load(&CreateContext, "eglCreateContext");
    load(&DestroyContext, "eglDestroyContext");
    load(&MakeCurrent, "eglMakeCurrent");
    load(&GetCurrentContext, "eglGetCurrentContext");
    if (!all) return std::string(kEglLibrary) + " lacks EGL 1.4 entry points";
    // The extensions' entry points come from eglGetProcAddress.
    const auto extension = [&](auto* fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(GetProcAddress(name));
    };
    extension(&QueryDevices, "eglQueryDevicesEXT");
    extension(&QueryDeviceString, "eglQueryDeviceStringEXT");
    extension(&GetPlatformDisplay, "eglGetPlatformDisplayEXT");
    if (!QueryDevices || !QueryDeviceString || !GetPlatformDisplay) {
      return "EGL lacks device enumeration (EGL_EXT_device_enumeration, EGL_EXT_platform_device)";
    }
    return "";
  }
};

// The process' back end, chosen once.
struct Backend {
  bool chosen = false;
  bool egl = false;
  EglApi api;
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLConfig config = nullptr;
  std::string renderer;      // GL_RENDERER of the first context
  std::string fallback_why;  // auto's reason for OSMesa
  std::string error_where, error;  // `egl` that EGL cannot honour: every context throws it
};

std::mutex& BackendMutex() {
  static std::mutex mutex;
  return mutex;
}

Backend& TheBackend() {
  static Backend backend;
  return backend;
}

bool IsSoftwareDevice(const EglApi& api, EGLDeviceEXT device) {
  const char* ext = api.QueryDeviceString(device, EGL_EXTENSIONS);
  return ext && std::strstr(ext, "EGL_MESA_device_software") != nullptr;
}

// An EGL context for desktop OpenGL (MuJoCo 2.2.2 needs the compatibility profile, EGL's
// default) on `display`, with no surface (EGL_KHR_surfaceless_context).
EGLContext CreateEglContext(const EglApi& api, EGLDisplay display, EGLConfig config) {
  if (!api.BindAPI(EGL_OPENGL_API)) return EGL_NO_CONTEXT;
  return api.CreateContext(display, config, EGL_NO_CONTEXT, nullptr);
}

// Sets up EGL on the device `choice` names. Returns "" with backend->display, config and
// renderer set, or why not. Touches nothing MuJoCo can see.
std::string SetUpEgl(const GlChoice& choice, Backend* backend) {
  EglApi& api = backend->api;
  std::string why = api.Open();
  if (!why.empty()) return why;
  EGLint count = 0;
  if (!api.QueryDevices(0, nullptr, &count) || count < 1) return "EGL enumerates no device";
  std::vector<EGLDeviceEXT> devices(count);
  api.QueryDevices(count, devices.data(), &count);
  int index = -1;
  if (choice.egl_device >= 0) {
    if (choice.egl_device >= count) {
      return "no EGL device " + std::to_string(choice.egl_device) + " (EGL enumerates " +
             std::to_string(count) + ")";
    }
    index = choice.egl_device;
  } else {
    for (int i = 0; i < count && index < 0; ++i) {
      if (!IsSoftwareDevice(api, devices[i])) index = i;
    }
    if (index < 0) {
      if (choice.kind == GlChoice::Kind::kAuto) return "EGL: no GPU device";
      index = 0;  // `egl` on a machine without a GPU: Mesa's software device
    }
  }
  EGLDisplay display = api.GetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[index], nullptr);
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !api.Initialize(display, &major, &minor)) {
    return "EGL device " + std::to_string(index) + ": eglInitialize failed (" +
           EglErrorText(api.GetError()) + ")";
  }
  // From here on a failure leaves no display open.
  const auto fail = [&](const std::string& why) {
    api.Terminate(display);
    return why;
  };
  const EGLint attributes[] = {EGL_RED_SIZE,        8,
                               EGL_GREEN_SIZE,      8,
                               EGL_BLUE_SIZE,       8,
                               EGL_ALPHA_SIZE,      8,
                               EGL_DEPTH_SIZE,      24,
                               EGL_STENCIL_SIZE,    8,
                               EGL_COLOR_BUFFER_TYPE, EGL_RGB_BUFFER,
                               EGL_SURFACE_TYPE,    EGL_PBUFFER_BIT,
                               EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                               EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  if (!api.ChooseConfig(display, attributes, &config, 1, &configs) || configs < 1) {
    return fail("EGL device " + std::to_string(index) + ": no RGBA8 + depth 24 OpenGL config");
  }
  // A trial context: where it works, so will the renderers'; its GL_RENDERER names the device.
  EGLContext trial = CreateEglContext(api, display, config);
  if (trial == EGL_NO_CONTEXT) {
    return fail("EGL device " + std::to_string(index) + ": no OpenGL context (" +
                EglErrorText(api.GetError()) + ")");
  }
  if (!api.MakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, trial)) {
    const EGLint error = api.GetError();
    api.DestroyContext(display, trial);
    return fail("EGL device " + std::to_string(index) + ": a context without a surface cannot "
                "be made current (" + EglErrorText(error) + ")");
  }
  using GetStringFn = const unsigned char* (*)(unsigned);
  auto get_string = reinterpret_cast<GetStringFn>(api.GetProcAddress("glGetString"));
  const unsigned char* name = get_string ? get_string(GL_RENDERER) : nullptr;
  backend->renderer = name ? reinterpret_cast<const char*>(name) : "unknown renderer";
  api.MakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  api.DestroyContext(display, trial);
  backend->display = display;
  backend->config = config;
  return "";
}

// Chooses the back end (see the header). Sets backend->chosen; for an `egl` that EGL cannot
// honour also backend->error, which MakeGlContext throws now and for every later context.
void Choose(Backend* backend) {
  backend->chosen = true;
  GlChoice choice;
  try {
    choice = GlChoiceFromEnvironment();
  } catch (const InputError& e) {
    backend->error_where = e.where();
    backend->error = e.message();
    return;
  }
  if (choice.kind == GlChoice::Kind::kOsmesa) return;
  std::string why = SetUpEgl(choice, backend);
  // From here on MuJoCo's loader finds eglGetProcAddress (see the header): promote libEGL to
  // the global namespace. Where that fails, OSMesa still works: libEGL stayed private.
  if (why.empty() && !dlopen(kEglLibrary, RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD)) {
    why = std::string("cannot make ") + kEglLibrary + " global (" + dlerror() + ")";
    backend->api.Terminate(backend->display);
  }
  if (why.empty()) {
    backend->egl = true;
  } else if (choice.kind == GlChoice::Kind::kEgl) {
    backend->error_where = GlChoiceWhere();
    backend->error = why;
  } else {
    backend->fallback_why = why;
    backend->renderer.clear();  // the GPU's name, from a trial context: OSMesa's comes later
  }
}

class OsmesaContext : public GlContext {
 public:
  OsmesaContext(int width, int height)
      : width_(width), height_(height), window_(static_cast<size_t>(4) * width * height) {
    context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
    if (!context_) throw std::runtime_error("OSMesaCreateContextExt failed");
    try {
      MakeCurrent();
    } catch (...) {
      OSMesaDestroyContext(context_);
      throw;
    }
  }
  ~OsmesaContext() override { OSMesaDestroyContext(context_); }
  void MakeCurrent() override {
    if (!OSMesaMakeCurrent(context_, window_.data(), GL_UNSIGNED_BYTE, width_, height_)) {
      throw std::runtime_error("OSMesaMakeCurrent failed");
    }
  }
  void Release() override {}  // OSMesa binds no context to a thread MuJoCo could not reuse

 private:
  int width_, height_;
  std::vector<unsigned char> window_;  // OSMesa's default framebuffer (unused by MuJoCo)
  OSMesaContext context_ = nullptr;
};

class EglContext : public GlContext {
 public:
  explicit EglContext(const Backend& backend) : api_(backend.api), display_(backend.display) {
    context_ = CreateEglContext(api_, display_, backend.config);
    if (context_ == EGL_NO_CONTEXT) {
      throw std::runtime_error("eglCreateContext failed (" + EglErrorText(api_.GetError()) + ")");
    }
    try {
      MakeCurrent();
    } catch (...) {
      api_.DestroyContext(display_, context_);
      throw;
    }
  }
  ~EglContext() override {
    Release();
    api_.DestroyContext(display_, context_);
  }
  void MakeCurrent() override {
    if (api_.GetCurrentContext() == context_) return;
    if (!api_.MakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
      throw std::runtime_error("eglMakeCurrent failed (" + EglErrorText(api_.GetError()) +
                               "; 0x3002 EGL_BAD_ACCESS: current on another thread)");
    }
  }
  void Release() override {
    if (api_.GetCurrentContext() == context_) {
      api_.MakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
  }

 private:
  const EglApi& api_;
  EGLDisplay display_;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

GlChoice ParseGlChoice(const std::string& text) {
  GlChoice choice;
  if (text.empty() || text == "auto") return choice;
  if (text == "osmesa") {
    choice.kind = GlChoice::Kind::kOsmesa;
    return choice;
  }
  if (text == "egl") {
    choice.kind = GlChoice::Kind::kEgl;
    return choice;
  }
  if (text.rfind("egl:", 0) == 0 && text.size() > 4 && text.size() <= 7 &&
      text.find_first_not_of("0123456789", 4) == std::string::npos) {
    choice.kind = GlChoice::Kind::kEgl;
    choice.egl_device = std::stoi(text.substr(4));
    return choice;
  }
  throw std::invalid_argument("'" + text + "' is not a GL back end (auto, osmesa, egl or egl:N)");
}

std::string GlChoiceWhere() {
  const char* env = std::getenv("TWINBENCH_GL");
  return std::string("TWINBENCH_GL=") + (env ? env : "");
}

GlChoice GlChoiceFromEnvironment() {
  const char* env = std::getenv("TWINBENCH_GL");
  try {
    return ParseGlChoice(env ? env : "");
  } catch (const std::invalid_argument& e) {
    throw InputError(GlChoiceWhere(), e.what());
  }
}

std::unique_ptr<GlContext> MakeGlContext(int width, int height) {
  std::lock_guard<std::mutex> lock(BackendMutex());
  Backend& backend = TheBackend();
  if (!backend.chosen) Choose(&backend);
  if (!backend.error.empty()) throw InputError(backend.error_where, backend.error);
  std::unique_ptr<GlContext> context;
  if (backend.egl) {
    context = std::make_unique<EglContext>(backend);
  } else {
    context = std::make_unique<OsmesaContext>(width, height);
    if (backend.renderer.empty()) {
      const unsigned char* name = glGetString(GL_RENDERER);  // OSMesa's own, linked
      backend.renderer = name ? reinterpret_cast<const char*>(name) : "unknown renderer";
    }
  }
  return context;
}

std::string GlBackendDescription() {
  std::lock_guard<std::mutex> lock(BackendMutex());
  const Backend& backend = TheBackend();
  if (!backend.chosen) return "none";
  std::string text = backend.egl ? "egl (" : "osmesa (";
  text += backend.renderer;
  if (!backend.fallback_why.empty()) text += "; " + backend.fallback_why;
  return text + ")";
}

}  // namespace twin
