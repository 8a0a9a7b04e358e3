#include "display/kms_display.hpp"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES2/gl2.h>
#include <gbm.h>
#include <xf86drm.h>
#include <xf86drmMode.h>

#include "display/letterbox_blit.hpp"
#include "gles/egl_context.hpp"
#include "gles/gl_objects.hpp"
#include "gles/render_target.hpp"

namespace probelight {

namespace {

constexpr const char* kHeadlessHint = "; without a screen, use --display headless";

// The off-screen frame (GL convention: its row 0 is the picture's bottom
// row, as composited) drawn over a viewport, unflipped.
void destroyFramebuffer(gbm_bo* bo, void* data) {
  const int fd = gbm_device_get_fd(gbm_bo_get_device(bo));
  const auto fb_id = static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(data));
  if (fb_id) drmModeRmFB(fd, fb_id);
}

}  // namespace

struct KmsDisplay::Gpu {
  std::unique_ptr<gles::EglContext> context;
  LetterboxBlit blit;
  gles::RenderTarget frame;  // composed at the camera's size, then scaled onto the screen
};

KmsDisplay::KmsDisplay(KmsDisplaySettings settings) : settings_(std::move(settings)) {}

KmsDisplay::~KmsDisplay() {
  gpu_.reset();
  if (shown_bo_ && surface_) gbm_surface_release_buffer(surface_, shown_bo_);
  if (surface_) gbm_surface_destroy(surface_);
  if (gbm_) gbm_device_destroy(gbm_);
  if (fd_ >= 0) {
    drmDropMaster(fd_);
    ::close(fd_);
  }
}

std::string KmsDisplay::describe() const {
  return "kms " + device_path_ + " " + mode_summary_ + (gpu_ && gpu_->context ? " (EGL " + gpu_->context->platformName() + ")" : "");
}

bool KmsDisplay::openDevice(std::string& error) {
  std::vector<std::string> candidates;
  if (!settings_.device.empty()) {
    candidates.push_back(settings_.device);
  } else {
    for (int i = 0; i < 8; ++i) {
      const std::string path = "/dev/dri/card" + std::to_string(i);
      if (std::filesystem::exists(path)) candidates.push_back(path);
    }
  }
  if (candidates.empty()) {
    error = "display: no KMS device (/dev/dri/card* absent: no GPU driver loaded? on a Raspberry Pi, "
            "dtoverlay=vc4-kms-v3d in config.txt)" + std::string(kHeadlessHint);
    return false;
  }
  std::string reasons;
  for (const std::string& path : candidates) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) {
      reasons += (reasons.empty() ? "" : "; ") + path + ": " + std::strerror(errno) +
                 (errno == EACCES ? " (is this user in the video group?)" : "");
      continue;
    }
    drmModeRes* resources = drmModeGetResources(fd);
    if (!resources) {  // a render-only node (the Pi 4's v3d is card0 or card1, the display the other)
      reasons += (reasons.empty() ? "" : "; ") + path + ": no display outputs";
      ::close(fd);
      continue;
    }
    std::vector<ConnectorDescription> connectors;
    std::vector<drmModeConnector*> raw;
    for (int i = 0; i < resources->count_connectors; ++i)
      if (drmModeConnector* c = drmModeGetConnector(fd, resources->connectors[i])) {
        connectors.push_back(describeConnector(*c));
        raw.push_back(c);
      }
    std::string choose_error;
    const std::optional<ModeChoice> choice = chooseMode(connectors, settings_.mode, choose_error);
    if (choice) {
      drmModeConnector* connector = raw[choice->connector_index];
      const drmModeModeInfo mode = connector->modes[choice->mode_index];
      // The CRTC: the one the connector's encoder drives now, else one its encoders can drive.
      std::uint32_t crtc = 0;
      if (drmModeEncoder* encoder = drmModeGetEncoder(fd, connector->encoder_id)) {
        crtc = encoder->crtc_id;
        drmModeFreeEncoder(encoder);
      }
      for (int e = 0; e < connector->count_encoders && !crtc; ++e)
        if (drmModeEncoder* encoder = drmModeGetEncoder(fd, connector->encoders[e])) {
          for (int k = 0; k < resources->count_crtcs && !crtc; ++k)
            if (encoder->possible_crtcs & (1u << k)) crtc = resources->crtcs[k];
          drmModeFreeEncoder(encoder);
        }
      for (drmModeConnector* c : raw) drmModeFreeConnector(c);
      drmModeFreeResources(resources);
      if (!crtc) {
        reasons += (reasons.empty() ? "" : "; ") + path + ": no display controller can drive " + choice->summary;
        ::close(fd);
        continue;
      }
      // Setting modes needs the DRM master role, which a running desktop holds.
      if (!drmIsMaster(fd) && drmSetMaster(fd) != 0) {
        error = "display: not DRM master on " + path + ": a desktop session (X or Wayland) holds the screen; "
                "stop it (sudo systemctl stop display-manager)" + std::string(kHeadlessHint);
        ::close(fd);
        return false;
      }
      fd_ = fd;
      device_path_ = path;
      connector_id_ = connectors[choice->connector_index].id;
      crtc_id_ = crtc;
      mode_summary_ = choice->summary;
      screen_width_ = mode.hdisplay;
      screen_height_ = mode.vdisplay;
      mode_ = mode;
      return true;
    }
    for (drmModeConnector* c : raw) drmModeFreeConnector(c);
    drmModeFreeResources(resources);
    reasons += (reasons.empty() ? "" : "; ") + path + ": " + choose_error;
    ::close(fd);
  }
  error = "display: " + reasons + std::string(kHeadlessHint);
  return false;
}

bool KmsDisplay::setUpEgl(std::string& error) {
  gbm_ = gbm_create_device(fd_);
  if (!gbm_) {
    error = "display: GBM cannot use " + device_path_;
    return false;
  }
  surface_ = gbm_surface_create(gbm_, static_cast<std::uint32_t>(screen_width_), static_cast<std::uint32_t>(screen_height_),
                                GBM_FORMAT_XRGB8888, GBM_BO_USE_SCANOUT | GBM_BO_USE_RENDERING);
  if (!surface_) {
    error = "display: cannot create a " + mode_summary_ + " scan-out surface";
    return false;
  }
  auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  EGLDisplay display = get_platform_display ? get_platform_display(EGL_PLATFORM_GBM_KHR, gbm_, nullptr)
                                            : eglGetDisplay(reinterpret_cast<EGLNativeDisplayType>(gbm_));
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor) || !eglBindAPI(EGL_OPENGL_ES_API)) {
    error = "display: EGL on GBM: " + gles::eglErrorName(eglGetError());
    return false;
  }
  // A config whose native visual is the surface's format.
  const EGLint attributes[] = {EGL_SURFACE_TYPE, EGL_WINDOW_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_ES2_BIT, EGL_RED_SIZE, 8,
                               EGL_GREEN_SIZE, 8, EGL_BLUE_SIZE, 8, EGL_NONE};
  EGLint count = 0;
  eglChooseConfig(display, attributes, nullptr, 0, &count);
  std::vector<EGLConfig> configs(static_cast<std::size_t>(std::max(count, 0)));
  eglChooseConfig(display, attributes, configs.data(), count, &count);
  EGLConfig config = nullptr;
  for (EGLConfig candidate : configs) {
    EGLint visual = 0;
    if (eglGetConfigAttrib(display, candidate, EGL_NATIVE_VISUAL_ID, &visual) && visual == GBM_FORMAT_XRGB8888) {
      config = candidate;
      break;
    }
  }
  if (!config) {
    error = "display: no EGL config renders to XRGB8888 scan-out buffers";
    eglTerminate(display);
    return false;
  }
  EGLContext context = gles::createGlesContext(display, config);
  EGLSurface surface = eglCreateWindowSurface(display, config, reinterpret_cast<EGLNativeWindowType>(surface_), nullptr);
  if (context == EGL_NO_CONTEXT || surface == EGL_NO_SURFACE) {
    error = "display: EGL context or window surface: " + gles::eglErrorName(eglGetError());
    eglTerminate(display);
    return false;
  }
  gpu_ = std::make_unique<Gpu>();
  gpu_->context = std::make_unique<gles::EglContext>(display, config, context, surface, gles::EglSurfaceKind::kWindow, "gbm");
  return gpu_->context->makeCurrent(error);
}

bool KmsDisplay::setUpOffscreen(int width_px, int height_px, std::string& error) {
  if (!gpu_->blit.init(error) || !gpu_->frame.init(width_px, height_px, error, gles::RenderTarget::Colour::kTexture)) {
    error = "display: off-screen frame: " + error;
    return false;
  }
  frame_width_ = width_px;
  frame_height_ = height_px;
  return gles::checkGl("KmsDisplay off-screen frame", error);
}

bool KmsDisplay::open(int width_px, int height_px, std::string& error) {
  return openDevice(error) && setUpEgl(error) && setUpOffscreen(width_px, height_px, error);
}

void KmsDisplay::beginFrame() { gpu_->frame.bind(); }

bool KmsDisplay::flip(gbm_bo* bo, std::string& error) {
  auto fb_id = static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(gbm_bo_get_user_data(bo)));
  if (!fb_id) {
    if (drmModeAddFB(fd_, gbm_bo_get_width(bo), gbm_bo_get_height(bo), 24, 32, gbm_bo_get_stride(bo),
                     gbm_bo_get_handle(bo).u32, &fb_id) != 0) {
      error = std::string("display: cannot make a scan-out buffer: ") + std::strerror(errno);
      return false;
    }
    gbm_bo_set_user_data(bo, reinterpret_cast<void*>(static_cast<std::uintptr_t>(fb_id)), destroyFramebuffer);
  }
  if (!crtc_set_) {
    if (drmModeSetCrtc(fd_, crtc_id_, fb_id, 0, 0, &connector_id_, 1, &mode_) != 0) {
      error = "display: cannot set " + mode_summary_ + ": " + std::strerror(errno);
      return false;
    }
    crtc_set_ = true;
    return true;
  }
  bool flipped = false;
  if (drmModePageFlip(fd_, crtc_id_, fb_id, DRM_MODE_PAGE_FLIP_EVENT, &flipped) != 0) {
    error = std::string("display: page flip: ") + std::strerror(errno);
    return false;
  }
  // Wait for the flip (vertical blank): at most one frame on the screen's clock.
  drmEventContext events{};
  events.version = 2;
  events.page_flip_handler = [](int, unsigned, unsigned, unsigned, void* data) { *static_cast<bool*>(data) = true; };
  while (!flipped) {
    pollfd poll_fd{fd_, POLLIN, 0};
    if (::poll(&poll_fd, 1, 1000) <= 0) {
      error = "display: no vertical blank for 1 s (" + mode_summary_ + ")";
      return false;
    }
    drmHandleEvent(fd_, &events);
  }
  return true;
}

bool KmsDisplay::present(std::uint64_t, std::string& error) {
  // The frame, scaled to fit the screen with its aspect kept, black around it.
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  gpu_->blit.draw(gpu_->frame.colourTexture(), frame_width_, frame_height_, screen_width_, screen_height_);
  if (!eglSwapBuffers(gpu_->context->display(), gpu_->context->surface())) {
    error = "display: eglSwapBuffers: " + gles::eglErrorName(eglGetError());
    return false;
  }
  gbm_bo* bo = gbm_surface_lock_front_buffer(surface_);
  if (!bo) {
    error = "display: no front buffer to show";
    return false;
  }
  if (!flip(bo, error)) {
    gbm_surface_release_buffer(surface_, bo);
    return false;
  }
  if (shown_bo_) gbm_surface_release_buffer(surface_, shown_bo_);
  shown_bo_ = bo;
  return true;
}

}  // namespace probelight
