#pragma once
// An off-screen OpenGL context for MuJoCo's renderer, with no window and no X server: EGL
// (a GPU's when one exists, else Mesa's surfaceless platform) or, as a fallback chosen at run
// time, OSMesa. Both libraries are opened with dlopen, so the binary links no GL library and
// OSMesa never meets libGL (with both loaded, gl* calls go nowhere).
//
// MuJoCo renders into its own off-screen framebuffer (mjFB_OFFSCREEN), so EGL needs no surface
// (EGL_KHR_surfaceless_context) and OSMesa only a small buffer of its own.
//
// Threading contract: one thread at a time. The context is current on the thread that created
// it; another thread calls MakeCurrent before using it (the previous thread must not use it
// any more). Construction and destruction happen on the thread that uses it.
//
// One backend per process: MuJoCo's GL loader takes its entry points from the first GL library
// it finds loaded, so OSMesa works only in a process where EGL never made a context.
#include <memory>
#include <string>

namespace urlab::render {

enum class GlBackend {
  kAuto,    // EGL, then OSMesa
  kEgl,     // EGL only
  kOsMesa,  // OSMesa only
};

// "auto", "egl", "osmesa"; throws Error naming `where` for anything else.
GlBackend ParseGlBackend(const std::string& text, const std::string& where);

class OffscreenGl {
 public:
  // Creates a compatibility-profile context (MuJoCo's mjr_* needs fixed-function GL) and makes
  // it current. The environment variable URLAB_GL (auto|egl|osmesa) overrides kAuto. Throws
  // Error listing what each backend tried when none works.
  static std::unique_ptr<OffscreenGl> Create(GlBackend backend = GlBackend::kAuto);
  virtual ~OffscreenGl() = default;
  OffscreenGl(const OffscreenGl&) = delete;
  OffscreenGl& operator=(const OffscreenGl&) = delete;

  // Makes the context current on the calling thread; false when the library refuses.
  virtual bool MakeCurrent() = 0;
  // Releases it from the calling thread.
  virtual void Release() = 0;
  // "egl (device 0)", "egl (surfaceless)", "osmesa": for logs and benchmarks.
  virtual std::string Describe() const = 0;

 protected:
  OffscreenGl() = default;
};

}  // namespace urlab::render
