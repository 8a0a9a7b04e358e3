#include "display/window_display.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <system_error>

#include <GLES2/gl2.h>
#include <SDL2/SDL.h>

#include "capture/rgb_image_io.hpp"
#include "gles/render_target.hpp"

namespace probelight {

namespace {

std::int64_t monotonicNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

WindowKey windowKey(SDL_Keycode key) {
  switch (key) {
    case SDLK_r:
    case SDLK_SPACE:
      return WindowKey::kButton;
    case SDLK_s:
      return WindowKey::kSave;
    case SDLK_q:
    case SDLK_ESCAPE:
      return WindowKey::kQuit;
    default:
      return WindowKey::kOther;
  }
}

}  // namespace

WindowDisplay::WindowDisplay(std::filesystem::path out_dir, WindowDisplaySettings settings)
    : out_dir_(std::move(out_dir)), settings_(settings), keys_(settings.long_press_ms) {}

WindowDisplay::~WindowDisplay() {
  writer_.reset();  // the saves still queued are written
  // GL objects go before their context, the context before its window.
  frame_.reset();
  blit_.reset();
  if (gl_context_) SDL_GL_DeleteContext(static_cast<SDL_GLContext>(gl_context_));
  if (window_) SDL_DestroyWindow(window_);
  if (window_ || gl_context_ || !video_driver_.empty()) SDL_QuitSubSystem(SDL_INIT_VIDEO);
}

bool WindowDisplay::open(int width_px, int height_px, std::string& error) {
  // GLES2 through EGL on X11 too (SDL would take GLX there), as on the
  // board; SDL loads libGLESv2, not desktop GL.
  SDL_SetHint(SDL_HINT_VIDEO_X11_FORCE_EGL, "1");
  SDL_SetHint(SDL_HINT_OPENGL_ES_DRIVER, "1");
  // The screensaver stays as the desktop has it.
  SDL_SetHint(SDL_HINT_VIDEO_ALLOW_SCREENSAVER, "1");
  const std::string no_window = "); without a desktop, use --display headless (frames written as PNG)";
  // A display server, X11 (XWayland too) before Wayland, as SDL 2 itself
  // prefers: SDL would otherwise fall back to its invisible "offscreen"
  // driver and show nothing. SDL_VIDEODRIVER, when set, is the user's.
  if (!std::getenv("SDL_VIDEODRIVER")) {
    if (std::getenv("DISPLAY")) {
      SDL_SetHint(SDL_HINT_VIDEODRIVER, "x11");
    } else if (std::getenv("WAYLAND_DISPLAY")) {
      SDL_SetHint(SDL_HINT_VIDEODRIVER, "wayland");
    } else {
      error = "display: no display server to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set" + no_window;
      return false;
    }
  }
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) {
    error = std::string("display: cannot reach the display server (SDL: ") + SDL_GetError() + no_window;
    return false;
  }
  video_driver_ = SDL_GetCurrentVideoDriver() ? SDL_GetCurrentVideoDriver() : "?";
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_ES);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 2);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 0);
  SDL_GL_SetAttribute(SDL_GL_RED_SIZE, 8);
  SDL_GL_SetAttribute(SDL_GL_GREEN_SIZE, 8);
  SDL_GL_SetAttribute(SDL_GL_BLUE_SIZE, 8);
  // The frame has its own depth buffer off-screen; the window needs none.
  SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 0);
  SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
  // At the frame's own size first (shown 1:1), resizable.
  window_ = SDL_CreateWindow("probelight", SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, width_px, height_px,
                             SDL_WINDOW_OPENGL | SDL_WINDOW_RESIZABLE);
  if (!window_) {
    error = std::string("display: cannot open a window on ") + video_driver_ + ": " + SDL_GetError();
    return false;
  }
  gl_context_ = SDL_GL_CreateContext(window_);
  if (!gl_context_ || SDL_GL_MakeCurrent(window_, static_cast<SDL_GLContext>(gl_context_)) != 0) {
    error = std::string("display: no GLES 2.0 context for the window on ") + video_driver_ + ": " + SDL_GetError();
    return false;
  }
  // Shown at the screen's refresh, as the board's page flips are; a
  // window system that cannot sync just shows at once.
  SDL_GL_SetSwapInterval(1);
  frame_ = std::make_unique<gles::RenderTarget>();
  blit_ = std::make_unique<LetterboxBlit>();
  if (!frame_->init(width_px, height_px, error, gles::RenderTarget::Colour::kTexture) || !blit_->init(error)) {
    error = "window display: " + error;
    return false;
  }
  frame_width_ = width_px;
  frame_height_ = height_px;
  writer_ = makePngWriteQueue();
  return true;
}

void WindowDisplay::beginFrame() { frame_->bind(); }

void WindowDisplay::pumpEvents() {
  SDL_Event event;
  while (SDL_PollEvent(&event)) {
    const std::int64_t now_ns = monotonicNowNs();
    if (event.type == SDL_QUIT) {
      pending_.quit = true;
    } else if (event.type == SDL_KEYDOWN || event.type == SDL_KEYUP) {
      pending_.add(keys_.onKey(windowKey(event.key.keysym.sym), event.type == SDL_KEYDOWN, event.key.repeat != 0,
                               now_ns));
    }
  }
  pending_.add(keys_.onTime(monotonicNowNs()));  // a held R becomes a long press while held
}

DisplayInput WindowDisplay::pollInput() {
  if (!window_) return {};
  pumpEvents();
  DisplayInput input;
  input.button = std::move(pending_.button);
  input.quit = pending_.quit;
  input.saves = pending_.saves;
  saves_due_ += pending_.saves;
  pending_ = WindowActions{};
  return input;
}

bool WindowDisplay::present(std::uint64_t frame_number, std::string& error) {
  // Keys pressed now reach the kiosk at its next pollInput (a save is
  // made at the present after it: the frame the kiosk's camera frame
  // belongs to).
  pumpEvents();
  if (saves_due_ > 0) {
    saves_due_ = 0;
    ImageRGB8 image;
    if (!frame_->readRGB(image, error)) return false;
    std::error_code ec;
    std::filesystem::create_directories(out_dir_, ec);
    const std::string path = (out_dir_ / numberedPngName("snapshot", frame_number)).string();
    if (!writer_->push(path, image, error)) {
      error = "window display: " + error;
      return false;
    }
    if (settings_.log) *settings_.log << "probelight: S: saving the frame shown as " << path << "\n";
  }
  int width = 0, height = 0;
  SDL_GL_GetDrawableSize(window_, &width, &height);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  blit_->draw(frame_->colourTexture(), frame_width_, frame_height_, width, height);
  SDL_GL_SwapWindow(window_);
  return true;
}

bool WindowDisplay::finish(std::string& error) {
  if (!writer_ || writer_->finish(error)) return true;
  error = "window display: " + error;
  return false;
}

std::string WindowDisplay::describe() const {
  if (!window_) return "window (closed)";
  return "window (SDL " + video_driver_ + ", EGL)";
}

}  // namespace probelight
