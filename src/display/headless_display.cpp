#include <system_error>

#include <GLES2/gl2.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "capture/rgb_image_io.hpp"
#include "display/display.hpp"
#include "display/kms_display.hpp"
#include "display/window_display.hpp"
#include "gles/egl_context.hpp"
#include "gles/render_target.hpp"

namespace probelight {

HeadlessDisplay::HeadlessDisplay(std::filesystem::path out_dir, int save_every)
    : out_dir_(std::move(out_dir)), save_every_(save_every) {}

HeadlessDisplay::~HeadlessDisplay() {
  writer_.reset();  // the frames still queued are written
  target_.reset();  // GL objects go before their context
  context_.reset();
}

bool HeadlessDisplay::open(int width_px, int height_px, std::string& error) {
  context_ = gles::EglContext::createHeadless(error);
  if (!context_) return false;
  target_ = std::make_unique<gles::RenderTarget>();
  if (!target_->init(width_px, height_px, error)) {
    error = "headless display: " + error;
    return false;
  }
  {
    std::error_code ec;
    std::filesystem::create_directories(out_dir_, ec);
    if (ec) {
      error = "headless display: cannot create " + out_dir_.string() + ": " + ec.message();
      return false;
    }
  }
  writer_ = makePngWriteQueue();
  return true;
}

void HeadlessDisplay::beginFrame() { target_->bind(); }

bool HeadlessDisplay::present(std::uint64_t frame_number, std::string& error) {
  const bool keep = keep_next_ || (save_every_ > 0 && frame_number % static_cast<std::uint64_t>(save_every_) == 0);
  keep_next_ = false;
  if (!keep) {
    glFlush();
    return true;
  }
  if (!target_->readRGB(last_kept_, error)) return false;
  last_kept_path_ = out_dir_ / numberedPngName("frame", frame_number);
  if (!writer_->push(last_kept_path_.string(), last_kept_, error)) {
    error = "headless display: " + error;
    return false;
  }
  return true;
}

bool HeadlessDisplay::finish(std::string& error) {
  if (!writer_ || writer_->finish(error)) return true;
  error = "headless display: " + error;
  return false;
}

std::string HeadlessDisplay::describe() const {
  if (!context_) return "headless (closed)";
  return "headless EGL (" + context_->platformName() + ")";
}

std::unique_ptr<Display> makeDisplay(const std::string& kind, const std::filesystem::path& out_dir, int save_every,
                                     const KmsDisplaySettings& kms, const WindowDisplaySettings& window,
                                     std::string& error) {
  if (kind == "headless") return std::make_unique<HeadlessDisplay>(out_dir, save_every);
  if (kind == "kms") return std::make_unique<KmsDisplay>(kms);
  if (kind == "window") return std::make_unique<WindowDisplay>(out_dir, window);
  error = "unknown display '" + kind + "' (choose headless, kms or window)";
  return nullptr;
}

}  // namespace probelight
