#include "gles/egl_context.hpp"
#include "gles/extension_list.hpp"

#include <cstdio>
#include <cstring>
#include <vector>

#include <EGL/eglext.h>

namespace probelight::gles {

namespace {

// Initializes `display`, picks an RGBA8 ES2 config and makes a context
// current, with a 1x1 pbuffer when `use_pbuffer`. Terminates the display on
// failure so callers can try the next platform.
std::unique_ptr<EglContext> finishContext(EGLDisplay display, bool use_pbuffer, const std::string& platform_name,
                                          std::string& why) {
  if (display == EGL_NO_DISPLAY) {
    why = "no display (" + eglErrorName(eglGetError()) + ")";
    return nullptr;
  }
  EGLint major = 0;
  EGLint minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    why = "eglInitialize failed (" + eglErrorName(eglGetError()) + ")";
    return nullptr;
  }
  auto fail = [&](const std::string& message) {
    why = message + " (" + eglErrorName(eglGetError()) + ")";
    eglTerminate(display);
    return nullptr;
  };
  const char* display_extensions = eglQueryString(display, EGL_EXTENSIONS);
  if (!use_pbuffer && !hasExtension(display_extensions, "EGL_KHR_surfaceless_context")) {
    why = "display lacks EGL_KHR_surfaceless_context";
    eglTerminate(display);
    return nullptr;
  }
  if (!eglBindAPI(EGL_OPENGL_ES_API)) return fail("eglBindAPI(EGL_OPENGL_ES_API) failed");
  const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES2_BIT,
                                      EGL_SURFACE_TYPE,    use_pbuffer ? EGL_PBUFFER_BIT : 0,
                                      EGL_RED_SIZE,        8,
                                      EGL_GREEN_SIZE,      8,
                                      EGL_BLUE_SIZE,       8,
                                      EGL_ALPHA_SIZE,      8,
                                      EGL_NONE};
  EGLConfig config = nullptr;
  EGLint config_count = 0;
  if (!eglChooseConfig(display, config_attributes, &config, 1, &config_count) || config_count < 1) {
    return fail("no RGBA8 OpenGL ES 2 config");
  }
  EGLContext context = createGlesContext(display, config);
  if (context == EGL_NO_CONTEXT) return fail("eglCreateContext(ES 3 or ES 2) failed");
  EGLSurface surface = EGL_NO_SURFACE;
  if (use_pbuffer) {
    const EGLint pbuffer_attributes[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    surface = eglCreatePbufferSurface(display, config, pbuffer_attributes);
    if (surface == EGL_NO_SURFACE) {
      eglDestroyContext(display, context);
      return fail("eglCreatePbufferSurface(1x1) failed");
    }
  }
  if (!eglMakeCurrent(display, surface, surface, context)) {
    if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
    eglDestroyContext(display, context);
    return fail("eglMakeCurrent failed");
  }
  return std::make_unique<EglContext>(display, config, context, surface,
                                      use_pbuffer ? EglSurfaceKind::kPbuffer : EglSurfaceKind::kNone, platform_name);
}

// The EGL's devices (EGL_EXT_device_enumeration), none where it lists none.
std::vector<EGLDeviceEXT> eglDevices() {
  auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  EGLint count = 0;
  if (query_devices == nullptr || !query_devices(0, nullptr, &count) || count <= 0) return {};
  std::vector<EGLDeviceEXT> devices(static_cast<size_t>(count));
  if (!query_devices(count, devices.data(), &count)) return {};
  devices.resize(static_cast<size_t>(count));
  return devices;
}

// Mesa's software EGL device (EGL_MESA_device_software), where the EGL lists
// devices and has one.
EGLDeviceEXT softwareDevice() {
  auto query_device_string =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
  if (query_device_string == nullptr) return EGL_NO_DEVICE_EXT;
  for (EGLDeviceEXT device : eglDevices())
    if (hasExtension(query_device_string(device, EGL_EXTENSIONS), "EGL_MESA_device_software")) return device;
  return EGL_NO_DEVICE_EXT;
}

// Whether `display` initialises and imports dmabufs without a surface.
bool importsDmabufsSurfaceless(EGLDisplay display) {
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, nullptr, nullptr)) return false;
  const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
  const bool imports = hasExtension(extensions, "EGL_EXT_image_dma_buf_import") &&
                       hasExtension(extensions, "EGL_KHR_surfaceless_context");
  eglTerminate(display);
  return imports;
}

}  // namespace

std::string displayDriverName(EGLDisplay display) {
  using GetDriverName = const char* (*)(EGLDisplay);
  auto get_driver_name = reinterpret_cast<GetDriverName>(eglGetProcAddress("eglGetDisplayDriverName"));
  const char* name = get_driver_name != nullptr ? get_driver_name(display) : nullptr;
  return name != nullptr ? name : "";
}

EGLContext createGlesContext(EGLDisplay display, EGLConfig config) {
  EGLint renderable = 0;
  eglGetConfigAttrib(display, config, EGL_RENDERABLE_TYPE, &renderable);
  const char* version = eglQueryString(display, EGL_VERSION);
  const bool egl_1_5_or_later = version != nullptr && (version[0] > '1' || std::strncmp(version, "1.5", 3) >= 0);
  const bool can_ask_for_es3 = egl_1_5_or_later || hasExtension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_create_context");
  if (can_ask_for_es3 && (renderable & EGL_OPENGL_ES3_BIT_KHR) != 0) {
    const EGLint es3[] = {EGL_CONTEXT_CLIENT_VERSION, 3, EGL_NONE};
    if (EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, es3); context != EGL_NO_CONTEXT)
      return context;
    // A driver (or MESA_GLES_VERSION_OVERRIDE=2.0) that lists ES 3 configs
    // but will not make the context: ES 2 below.
  }
  const EGLint es2[] = {EGL_CONTEXT_CLIENT_VERSION, 2, EGL_NONE};
  return eglCreateContext(display, config, EGL_NO_CONTEXT, es2);
}

std::string eglErrorName(EGLint code) {
  const char* name = "unknown EGL error";
  switch (code) {
    case EGL_SUCCESS: name = "EGL_SUCCESS"; break;
    case EGL_NOT_INITIALIZED: name = "EGL_NOT_INITIALIZED"; break;
    case EGL_BAD_ACCESS: name = "EGL_BAD_ACCESS"; break;
    case EGL_BAD_ALLOC: name = "EGL_BAD_ALLOC"; break;
    case EGL_BAD_ATTRIBUTE: name = "EGL_BAD_ATTRIBUTE"; break;
    case EGL_BAD_CONFIG: name = "EGL_BAD_CONFIG"; break;
    case EGL_BAD_CONTEXT: name = "EGL_BAD_CONTEXT"; break;
    case EGL_BAD_CURRENT_SURFACE: name = "EGL_BAD_CURRENT_SURFACE"; break;
    case EGL_BAD_DISPLAY: name = "EGL_BAD_DISPLAY"; break;
    case EGL_BAD_MATCH: name = "EGL_BAD_MATCH"; break;
    case EGL_BAD_NATIVE_PIXMAP: name = "EGL_BAD_NATIVE_PIXMAP"; break;
    case EGL_BAD_NATIVE_WINDOW: name = "EGL_BAD_NATIVE_WINDOW"; break;
    case EGL_BAD_PARAMETER: name = "EGL_BAD_PARAMETER"; break;
    case EGL_BAD_SURFACE: name = "EGL_BAD_SURFACE"; break;
    case EGL_CONTEXT_LOST: name = "EGL_CONTEXT_LOST"; break;
    default: break;
  }
  char text[64];
  std::snprintf(text, sizeof text, "%s (0x%04X)", name, static_cast<unsigned>(code));
  return text;
}

EglContext::EglContext(EGLDisplay display, EGLConfig config, EGLContext context, EGLSurface surface,
                       EglSurfaceKind surface_kind, std::string platform_name)
    : display_(display),
      config_(config),
      context_(context),
      surface_(surface),
      surface_kind_(surface_kind),
      platform_name_(std::move(platform_name)) {}

EglContext::~EglContext() {
  if (display_ == EGL_NO_DISPLAY) return;
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
  if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
  eglTerminate(display_);
}

bool EglContext::makeCurrent(std::string& error) const {
  if (eglMakeCurrent(display_, surface_, surface_, context_)) return true;
  error = "eglMakeCurrent failed: " + eglErrorName(eglGetError()) +
          ". Is the context current on another thread? An EGL context can be current on only one thread at a time.";
  return false;
}

std::unique_ptr<EglContext> EglContext::createHeadless(std::string& error) {
  std::string attempts;
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  const bool has_platform_base = get_platform_display != nullptr && hasExtension(client_extensions, "EGL_EXT_platform_base");
  const bool has_platform_device = has_platform_base && hasExtension(client_extensions, "EGL_EXT_platform_device");

  if (has_platform_base && hasExtension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    std::string why;
    EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (auto context = finishContext(display, false, "surfaceless", why)) {
      // Where a DRM device has no driver that renders (a virtual machine's
      // display-only virtio-gpu), Mesa's surfaceless platform renders with
      // llvmpipe through that device (kms_swrast), and a camera's dmabuf is
      // then imported through the display driver, which may refuse it.
      // Headless rendering needs no display: the same llvmpipe on Mesa's
      // software device maps an imported dmabuf itself. It is taken where it
      // offers the import; the surfaceless context otherwise.
      if (!has_platform_device || displayDriverName(display) != "kms_swrast") return context;
      EGLDisplay software = EGL_NO_DISPLAY;
      if (EGLDeviceEXT device = softwareDevice(); device != EGL_NO_DEVICE_EXT)
        software = get_platform_display(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
      if (!importsDmabufsSurfaceless(software)) return context;
      context.reset();  // releases the thread's current context before the next is made current
      if (auto software_context =
              finishContext(software, false, "Mesa's software device, not surfaceless's kms_swrast", why))
        return software_context;
      attempts += "\n  Mesa's software device (after surfaceless gave kms_swrast): " + why;
      if (auto again = finishContext(display, false, "surfaceless", why)) return again;
    }
    attempts += "\n  EGL_MESA_platform_surfaceless: " + why;
  } else {
    attempts += "\n  EGL_MESA_platform_surfaceless: not offered by this EGL";
  }

  if (has_platform_device) {
    const std::vector<EGLDeviceEXT> devices = eglDevices();
    if (!devices.empty()) {
      for (size_t i = 0; i < devices.size(); ++i) {
        std::string why;
        EGLDisplay display = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (auto context = finishContext(display, false, "device", why)) return context;
        attempts += "\n  EGL_EXT_platform_device #" + std::to_string(i) + ": " + why;
      }
    } else {
      attempts += "\n  EGL_EXT_platform_device: no EGL devices";
    }
  } else {
    attempts += "\n  EGL_EXT_platform_device: not offered by this EGL";
  }

  {
    std::string why;
    if (auto context = finishContext(eglGetDisplay(EGL_DEFAULT_DISPLAY), true, "default+pbuffer", why)) return context;
    attempts += "\n  eglGetDisplay(EGL_DEFAULT_DISPLAY) + pbuffer: " + why;
  }
  error =
      "Could not create a headless OpenGL ES 2 context. Tried:" + attempts +
      "\nInstall Mesa's EGL and GLES drivers (Debian: libegl1-mesa, libgles2-mesa, libgl1-mesa-dri), check that "
      "/dev/dri is readable by this user (group 'render' or 'video'), or set LIBGL_ALWAYS_SOFTWARE=1 to use llvmpipe.";
  return nullptr;
}

}  // namespace probelight::gles
