// The display seam. A display owns the GL context (it decides how the context
// is made: surfaceless EGL here, GBM/KMS on the board) and the drawable that
// each frame is composited into.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "display/image_write_queue.hpp"
#include "input/button_source.hpp"

namespace probelight {

namespace gles {
class EglContext;
class RenderTarget;
}  // namespace gles

// What the user asked through the display itself (a desktop window's
// keys) since the last poll.
struct DisplayInput {
  std::vector<ButtonEvent::Kind> button;  // presses of the window's button key, in order
  bool quit = false;                      // Q, Esc, or the window closed
  int saves = 0;  // S: the display saves the frame it shows; the kiosk, the camera's frame under it
};

class Display {
 public:
  virtual ~Display() = default;
  // Creates the context (current on the calling thread on return) and a
  // drawable of the camera frame's size. False with a one-line reason.
  virtual bool open(int width_px, int height_px, std::string& error) = 0;
  // Binds the drawable and sets the viewport to it.
  virtual void beginFrame() = 0;
  // Shows the finished frame. `frame_number` names it where frames are kept.
  virtual bool present(std::uint64_t frame_number, std::string& error) = 0;
  virtual std::string name() const = 0;
  // Platform and renderer, for the report.
  virtual std::string describe() const = 0;
  // Keep the next presented frame whatever else the display keeps (the last
  // frame of a run, say); a display that keeps no frames ignores it.
  virtual void keepNextFrame() {}
  // Input through the display since the last call (none for a display
  // without keys). Never blocks.
  virtual DisplayInput pollInput() { return {}; }
  // A line for the status bar while the kiosk starts (a window's keys), or "".
  virtual std::string startupHint() const { return ""; }
  // Waits for the work present() left running (frames still being written).
  // False with a one-line reason when some of it failed.
  virtual bool finish(std::string& error) {
    (void)error;
    return true;
  }
};

// EGL without a display server (Mesa surfaceless); each presented frame is
// read back and written as DIR/frame_NNNNNN.png when its number is a multiple
// of save_every (0: never), and always when present() is asked to keep it.
// The PNGs are encoded and written on a thread of their own
// (ImageWriteQueue): a failed write is reported by a later present() or by
// finish().
class HeadlessDisplay final : public Display {
 public:
  HeadlessDisplay(std::filesystem::path out_dir, int save_every);
  ~HeadlessDisplay() override;

  bool open(int width_px, int height_px, std::string& error) override;
  void beginFrame() override;
  bool present(std::uint64_t frame_number, std::string& error) override;
  std::string name() const override { return "headless"; }
  std::string describe() const override;

  // Whatever save_every says.
  void keepNextFrame() override { keep_next_ = true; }
  // The last frame read back (empty if none was kept yet).
  const ImageRGB8& lastKeptFrame() const { return last_kept_; }
  const std::filesystem::path& lastKeptPath() const { return last_kept_path_; }
  int framesWritten() const { return writer_ ? writer_->written() : 0; }
  bool finish(std::string& error) override;

 private:
  std::filesystem::path out_dir_;
  int save_every_;
  bool keep_next_ = false;
  std::unique_ptr<gles::EglContext> context_;
  std::unique_ptr<gles::RenderTarget> target_;
  ImageRGB8 last_kept_;
  std::filesystem::path last_kept_path_;
  std::unique_ptr<ImageWriteQueue> writer_;
};

struct KmsDisplaySettings;
struct WindowDisplaySettings;

// "headless" (out_dir, save_every), "kms" (the board's screen, `kms`) or
// "window" (a desktop window, `window`; its saves go to out_dir).
std::unique_ptr<Display> makeDisplay(const std::string& kind, const std::filesystem::path& out_dir, int save_every,
                                     const KmsDisplaySettings& kms, const WindowDisplaySettings& window,
                                     std::string& error);

}  // namespace probelight
