#include "render/gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/osmesa.h>
#include <dlfcn.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdlib>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::render {

namespace {

// A library opened at run time, closed with its owner.
class Library {
 public:
  explicit Library(const char* const* names) {
    for (; *names && !handle_; ++names) handle_ = ::dlopen(*names, RTLD_NOW | RTLD_LOCAL);
  }
  ~Library() {
    if (handle_) ::dlclose(handle_);
  }
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;
  bool ok() const { return handle_ != nullptr; }
  template <typename F>
  F Get(const char* name) const {
    return reinterpret_cast<F>(::dlsym(handle_, name));
  }

 private:
  void* handle_ = nullptr;
};

constexpr const char* kEglNames[] = {"libEGL.so.1", "libEGL.so", nullptr};
constexpr const char* kOsMesaNames[] = {"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so",
                                        nullptr};

// ---- EGL ----

struct EglApi {
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLTERMINATEPROC Terminate = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplay = nullptr;
  PFNEGLQUERYDEVICESEXTPROC QueryDevices = nullptr;
};

class EglContext final : public OffscreenGl {
 public:
  EglContext(std::unique_ptr<Library> lib, EglApi api, EGLDisplay display, EGLContext context,
             std::string what)
      : lib_(std::move(lib)),
        api_(api),
        display_(display),
        context_(context),
        what_(std::move(what)) {}
  ~EglContext() override {
    api_.MakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    api_.DestroyContext(display_, context_);
    api_.Terminate(display_);
  }
  bool MakeCurrent() override {
    return api_.MakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) == EGL_TRUE;
  }
  void Release() override {
    api_.MakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  std::string Describe() const override { return what_; }

 private:
  std::unique_ptr<Library> lib_;
  EglApi api_;
  EGLDisplay display_;
  EGLContext context_;
  std::string what_;
};

// A compatibility context on `display`, current; nullptr (and `why` filled) when it fails.
EGLContext TryEglDisplay(const EglApi& api, EGLDisplay display, std::string& why) {
  if (display == EGL_NO_DISPLAY) {
    why = "no display";
    return EGL_NO_CONTEXT;
  }
  EGLint major = 0, minor = 0;
  if (!api.Initialize(display, &major, &minor)) {
    why = fmt::format("eglInitialize failed (0x{:x})", api.GetError());
    return EGL_NO_CONTEXT;
  }
  // Without EGL_PBUFFER_BIT no config of Mesa's surfaceless platform matches.
  const EGLint config_attribs[] = {EGL_SURFACE_TYPE,
                                   EGL_PBUFFER_BIT,
                                   EGL_RENDERABLE_TYPE,
                                   EGL_OPENGL_BIT,
                                   EGL_RED_SIZE,
                                   8,
                                   EGL_GREEN_SIZE,
                                   8,
                                   EGL_BLUE_SIZE,
                                   8,
                                   EGL_ALPHA_SIZE,
                                   8,
                                   EGL_DEPTH_SIZE,
                                   24,
                                   EGL_STENCIL_SIZE,
                                   8,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  if (!api.ChooseConfig(display, config_attribs, &config, 1, &count) || count < 1) {
    why = "no RGBA8/depth24/stencil8 pbuffer config";
    api.Terminate(display);
    return EGL_NO_CONTEXT;
  }
  if (!api.BindAPI(EGL_OPENGL_API)) {
    why = "eglBindAPI(EGL_OPENGL_API) failed";
    api.Terminate(display);
    return EGL_NO_CONTEXT;
  }
  const EGLint context_attribs[] = {EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT, EGL_NONE};
  EGLContext context = api.CreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT) {
    why = fmt::format("no compatibility context (0x{:x})", api.GetError());
    api.Terminate(display);
    return EGL_NO_CONTEXT;
  }
  if (!api.MakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    why = fmt::format("surfaceless eglMakeCurrent failed (0x{:x})", api.GetError());
    api.DestroyContext(display, context);
    api.Terminate(display);
    return EGL_NO_CONTEXT;
  }
  return context;
}

std::unique_ptr<OffscreenGl> TryEgl(std::string& why) {
  auto lib = std::make_unique<Library>(kEglNames);
  if (!lib->ok()) {
    why = "libEGL.so.1 not found (package libegl1)";
    return nullptr;
  }
  EglApi api;
  api.GetProcAddress = lib->Get<PFNEGLGETPROCADDRESSPROC>("eglGetProcAddress");
  api.Initialize = lib->Get<PFNEGLINITIALIZEPROC>("eglInitialize");
  api.Terminate = lib->Get<PFNEGLTERMINATEPROC>("eglTerminate");
  api.ChooseConfig = lib->Get<PFNEGLCHOOSECONFIGPROC>("eglChooseConfig");
  api.BindAPI = lib->Get<PFNEGLBINDAPIPROC>("eglBindAPI");
  api.CreateContext = lib->Get<PFNEGLCREATECONTEXTPROC>("eglCreateContext");
  api.DestroyContext = lib->Get<PFNEGLDESTROYCONTEXTPROC>("eglDestroyContext");
  api.MakeCurrent = lib->Get<PFNEGLMAKECURRENTPROC>("eglMakeCurrent");
  api.GetError = lib->Get<PFNEGLGETERRORPROC>("eglGetError");
  if (!api.GetProcAddress || !api.Initialize || !api.Terminate || !api.ChooseConfig ||
      !api.BindAPI || !api.CreateContext || !api.DestroyContext || !api.MakeCurrent ||
      !api.GetError) {
    why = "libEGL lacks EGL 1.4 entry points";
    return nullptr;
  }
  // Without DISPLAY, eglGetDisplay(EGL_DEFAULT_DISPLAY) fails: ask for a platform display.
  api.GetPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      api.GetProcAddress("eglGetPlatformDisplayEXT"));
  api.QueryDevices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(api.GetProcAddress("eglQueryDevicesEXT"));
  if (!api.GetPlatformDisplay) {
    why = "no eglGetPlatformDisplayEXT";
    return nullptr;
  }
  std::vector<std::string> tried;
  // A GPU first (the device platform lists hardware devices before Mesa's software one).
  if (api.QueryDevices) {
    EGLDeviceEXT devices[8];
    EGLint n = 0;
    if (api.QueryDevices(8, devices, &n)) {
      for (EGLint i = 0; i < n; ++i) {
        std::string reason;
        EGLDisplay display = api.GetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        EGLContext context = TryEglDisplay(api, display, reason);
        if (context != EGL_NO_CONTEXT) {
          return std::make_unique<EglContext>(std::move(lib), api, display, context,
                                              fmt::format("egl (device {})", i));
        }
        tried.push_back(fmt::format("device {}: {}", i, reason));
      }
    }
  }
  std::string reason;
  EGLDisplay display =
      api.GetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  EGLContext context = TryEglDisplay(api, display, reason);
  if (context != EGL_NO_CONTEXT) {
    return std::make_unique<EglContext>(std::move(lib), api, display, context, "egl (surfaceless)");
  }
  tried.push_back("surfaceless: " + reason);
  why = fmt::format("{}", fmt::join(tried, "; "));
  return nullptr;
}

// ---- OSMesa ----

using OSMesaCreateContextExtFn = OSMesaContext (*)(GLenum, GLint, GLint, GLint, OSMesaContext);
using OSMesaDestroyContextFn = void (*)(OSMesaContext);
using OSMesaMakeCurrentFn = GLboolean (*)(OSMesaContext, void*, GLenum, GLsizei, GLsizei);

class OsMesaContext final : public OffscreenGl {
 public:
  OsMesaContext(std::unique_ptr<Library> lib, OSMesaContext context)
      : lib_(std::move(lib)), context_(context) {
    destroy_ = lib_->Get<OSMesaDestroyContextFn>("OSMesaDestroyContext");
    make_current_ = lib_->Get<OSMesaMakeCurrentFn>("OSMesaMakeCurrent");
  }
  ~OsMesaContext() override {
    if (destroy_) destroy_(context_);
  }
  bool MakeCurrent() override {
    // A small default framebuffer: MuJoCo draws into its own off-screen one.
    return make_current_ &&
           make_current_(context_, buffer_.data(), GL_UNSIGNED_BYTE, kSide, kSide) != 0;
  }
  void Release() override {}
  std::string Describe() const override { return "osmesa"; }

 private:
  static constexpr int kSide = 16;
  std::unique_ptr<Library> lib_;
  OSMesaContext context_;
  OSMesaDestroyContextFn destroy_ = nullptr;
  OSMesaMakeCurrentFn make_current_ = nullptr;
  std::vector<unsigned char> buffer_ = std::vector<unsigned char>(4 * kSide * kSide);
};

std::unique_ptr<OffscreenGl> TryOsMesa(std::string& why) {
  auto lib = std::make_unique<Library>(kOsMesaNames);
  if (!lib->ok()) {
    why = "libOSMesa.so.8 not found (package libosmesa6)";
    return nullptr;
  }
  auto create = lib->Get<OSMesaCreateContextExtFn>("OSMesaCreateContextExt");
  if (!create) {
    why = "libOSMesa lacks OSMesaCreateContextExt";
    return nullptr;
  }
  OSMesaContext context = create(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!context) {
    why = "OSMesaCreateContextExt failed";
    return nullptr;
  }
  auto gl = std::make_unique<OsMesaContext>(std::move(lib), context);
  if (!gl->MakeCurrent()) {
    why = "OSMesaMakeCurrent failed";
    return nullptr;
  }
  return gl;
}

}  // namespace

GlBackend ParseGlBackend(const std::string& text, const std::string& where) {
  if (text == "auto" || text.empty()) return GlBackend::kAuto;
  if (text == "egl") return GlBackend::kEgl;
  if (text == "osmesa") return GlBackend::kOsMesa;
  throw Error(where + ": the GL backend must be auto, egl or osmesa, not '" + text + "'");
}

std::unique_ptr<OffscreenGl> OffscreenGl::Create(GlBackend backend) {
  if (backend == GlBackend::kAuto) {
    if (const char* env = std::getenv("URLAB_GL")) backend = ParseGlBackend(env, "URLAB_GL");
  }
  std::vector<std::string> tried;
  std::string why;
  if (backend != GlBackend::kOsMesa) {
    if (auto gl = TryEgl(why)) return gl;
    tried.push_back("EGL: " + why);
  }
  if (backend != GlBackend::kEgl) {
    if (auto gl = TryOsMesa(why)) return gl;
    tried.push_back("OSMesa: " + why);
  }
  throw Error(
      fmt::format("no off-screen OpenGL context ({}); install libegl1 and "
                  "libgl1-mesa-dri, or libosmesa6",
                  fmt::join(tried, "; ")));
}

}  // namespace urlab::render
