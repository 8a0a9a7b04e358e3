// A window on the desktop (X11 or Wayland) through SDL2, for trying
// probelight on a laptop (--display window). SDL2 is what libcamera's own
// `cam` opens its window with; the GLES2 context comes through EGL, as on
// the board. The frame is composed at the camera's size off-screen and
// drawn into the window scaled to fit with its aspect kept
// (LetterboxBlit), so resizing the window never stretches it.
//
// The window's keys (input/window_keys.hpp) reach the kiosk through
// pollInput(): R or space is the button, Q, Esc or closing the window
// quits. S saves the frame now shown as OUT/snapshot_NNNNNN.png, here.
#pragma once

#include <filesystem>
#include <memory>
#include <ostream>
#include <string>

#include "display/display.hpp"
#include "display/letterbox_blit.hpp"
#include "input/window_keys.hpp"

struct SDL_Window;

namespace probelight {

namespace gles {
class RenderTarget;
}

struct WindowDisplaySettings {
  double long_press_ms = 3000.0;  // button.long_press_ms: R held this long
  std::ostream* log = nullptr;    // where a saved frame is said (none: not said)
};

class WindowDisplay final : public Display {
 public:
  WindowDisplay(std::filesystem::path out_dir, WindowDisplaySettings settings);
  ~WindowDisplay() override;

  // False with one line when there is no window system to open a window
  // on (no DISPLAY or WAYLAND_DISPLAY, or neither answers), suggesting
  // --display headless, or when the window gets no GLES2 context.
  bool open(int width_px, int height_px, std::string& error) override;
  void beginFrame() override;
  bool present(std::uint64_t frame_number, std::string& error) override;
  std::string name() const override { return "window"; }
  std::string describe() const override;
  DisplayInput pollInput() override;
  std::string startupHint() const override { return WindowKeys::help(); }
  bool finish(std::string& error) override;

 private:
  void pumpEvents();

  std::filesystem::path out_dir_;
  WindowDisplaySettings settings_;
  SDL_Window* window_ = nullptr;
  void* gl_context_ = nullptr;  // SDL_GLContext
  std::string video_driver_;
  int frame_width_ = 0, frame_height_ = 0;
  std::unique_ptr<gles::RenderTarget> frame_;
  std::unique_ptr<LetterboxBlit> blit_;
  WindowKeys keys_;
  WindowActions pending_;  // since the last pollInput (saves: done at the next present)
  int saves_due_ = 0;
  std::unique_ptr<ImageWriteQueue> writer_;
};

}  // namespace probelight
