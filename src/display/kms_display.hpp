// Fullscreen on the board's screen through DRM/KMS and GBM, with no X or
// Wayland: EGL on a GBM surface, a frame composited off-screen at the
// camera's size, scaled (letterboxed) onto the screen's mode, and shown by a
// page flip that waits for vertical blank.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "display/display.hpp"
#include "display/kms_modes.hpp"

struct gbm_device;
struct gbm_surface;
struct gbm_bo;

namespace probelight {

struct KmsDisplaySettings {
  std::string device;  // e.g. /dev/dri/card1; empty: the first card with a screen connected
  ModeRequest mode;
};

class KmsDisplay final : public Display {
 public:
  explicit KmsDisplay(KmsDisplaySettings settings);
  ~KmsDisplay() override;
  // False, with a one-line reason and `--display headless` suggested, when
  // there is no KMS device, no screen, or another program (a desktop
  // session) is the DRM master.
  bool open(int width_px, int height_px, std::string& error) override;
  void beginFrame() override;
  bool present(std::uint64_t frame_number, std::string& error) override;
  std::string name() const override { return "kms"; }
  std::string describe() const override;

 private:
  struct Gpu;
  bool openDevice(std::string& error);
  bool setUpEgl(std::string& error);
  bool setUpOffscreen(int width_px, int height_px, std::string& error);
  bool flip(gbm_bo* bo, std::string& error);

  KmsDisplaySettings settings_;
  std::string device_path_;
  int fd_ = -1;
  std::uint32_t connector_id_ = 0, crtc_id_ = 0;
  std::string mode_summary_;
  drmModeModeInfo mode_{};
  int screen_width_ = 0, screen_height_ = 0;
  int frame_width_ = 0, frame_height_ = 0;
  gbm_device* gbm_ = nullptr;
  gbm_surface* surface_ = nullptr;
  gbm_bo* shown_bo_ = nullptr;
  bool crtc_set_ = false;
  std::unique_ptr<Gpu> gpu_;  // EGL context and GL objects (pimpl: keeps GL out of this header)
};

}  // namespace probelight
