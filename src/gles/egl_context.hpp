// EGL display + OpenGL ES context (ES 3 where offered, GLSL ES 1.00 shaders). The handles live in EglContext; how the display
// and the drawable were obtained (surfaceless, EGL device, pbuffer, and later
// GBM/KMS) is the factory's business, so a KMS output can reuse everything
// here and only add its own factory and surface kind.
#pragma once

#include <memory>
#include <string>

#include <EGL/egl.h>

namespace probelight::gles {

enum class EglSurfaceKind {
  kNone,     // EGL_KHR_surfaceless_context: render only into FBOs
  kPbuffer,  // 1x1 pbuffer, for displays that cannot make a context current without a surface
  kWindow,   // reserved for a GBM/KMS scan-out surface
};

class EglContext {
 public:
  // Headless GLES2 context with no display server. Tries, in order,
  // EGL_MESA_platform_surfaceless, EGL_EXT_platform_device and the default
  // display with a 1x1 pbuffer; where surfaceless gives Mesa's kms_swrast
  // (llvmpipe through a DRM device that cannot render), Mesa's software
  // device instead if it imports dmabufs. On failure returns null and
  // explains every attempt in `error`. The context is current on the
  // calling thread on return.
  static std::unique_ptr<EglContext> createHeadless(std::string& error);

  // Takes ownership of already-created handles (used by factories, including
  // a future GBM one). `surface` may be EGL_NO_SURFACE.
  EglContext(EGLDisplay display, EGLConfig config, EGLContext context, EGLSurface surface, EglSurfaceKind surface_kind,
             std::string platform_name);
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  bool makeCurrent(std::string& error) const;

  EGLDisplay display() const { return display_; }
  EGLConfig config() const { return config_; }
  EGLContext context() const { return context_; }
  EGLSurface surface() const { return surface_; }
  EglSurfaceKind surfaceKind() const { return surface_kind_; }
  // "surfaceless", "device", "default+pbuffer", ...: for logs.
  const std::string& platformName() const { return platform_name_; }

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLConfig config_ = nullptr;
  EGLContext context_ = EGL_NO_CONTEXT;
  EGLSurface surface_ = EGL_NO_SURFACE;
  EglSurfaceKind surface_kind_ = EglSurfaceKind::kNone;
  std::string platform_name_;
};

// The display's driver as Mesa names it (EGL_MESA_query_driver: "swrast",
// "kms_swrast", "v3d", ...), or "" where the EGL does not say.
std::string displayDriverName(EGLDisplay display);

// Human-readable name of an EGL error code, e.g. "EGL_BAD_MATCH (0x3009)".
std::string eglErrorName(EGLint code);

// An OpenGL ES context on `config`: ES 3 where the config renders ES 3 and
// the display can make one (EGL 1.5 or EGL_KHR_create_context), else ES 2.
// The shaders are GLSL ES 1.00 either way, which every ES 3 context runs;
// what ES 3 adds is the sized RGBA16F render target (V3D, the Pi 4's GPU,
// offers half-float rendering only that way). EGL_NO_CONTEXT on failure.
// Configs are chosen with EGL_OPENGL_ES2_BIT, which every ES 3 config has too.
EGLContext createGlesContext(EGLDisplay display, EGLConfig config);

}  // namespace probelight::gles
