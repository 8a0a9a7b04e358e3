// Frames from the simulated world, on the capture thread, with their truth.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "capture/exposure_schedule.hpp"
#include "capture/frame_source.hpp"
#include "capture/lens_focus_choice.hpp"
#include "sim/world.hpp"

namespace probelight {

// `rgb` as the simulated camera delivers it in `layout`: kRgb8 as is (with
// its luma), kI420 or kNv12 encoded as the board's ISP does and kYuyv as a
// webcam does (sim/camera_ycbcr.hpp: full-range Rec601), the packed RGB
// layouts in their byte order, each with its luma.
void encodeSimFrame(const ImageRGB8& rgb, PixelLayout layout, FrameBuffer& frame);

struct SimCameraOptions {
  // kRgb8, or any camera layout (I420, NV12, YUYV, RGB888, BGR888, XRGB8888)
  // as a camera gives it.
  PixelLayout layout = PixelLayout::kRgb8;
  // A camera that disappears: frame `lost_at_frame` fails ("disconnected"),
  // then the next `failed_restarts` start() calls fail; the one after
  // succeeds and frames go on from where they stopped. -1: never.
  std::int64_t lost_at_frame = -1;
  // A camera that goes silent: frame `silent_at_frame` comes `silent_s`
  // seconds late (once), the stream open all along. -1: never.
  std::int64_t silent_at_frame = -1;
  double silent_s = 0.0;
  // The sensor's shortest exposure (microseconds; 0: any): a manual
  // exposure below it is taken at it, and the metadata says so.
  double min_exposure_us = 0.0;
  // Whether shortestExposureUs() says it (real sources may not know).
  bool min_exposure_reported = true;
  // false: a sensor with no exposure control (vimc's): a ladder is refused,
  // as LibcameraSource refuses it for such a camera.
  bool exposure_controllable = true;
  int failed_restarts = 0;
  // The sensor's own exposure outside a bracket, in stops from the scene's.
  double exposure_stops = 0.0;
  // Auto exposure and white balance moving (issue 19's camera response):
  // from frame response_shift_from_frame up to (not including)
  // response_shift_until_frame (-1: to the end) every frame outside a
  // bracket is taken exposure_shift_stops further, and with its red and
  // blue multiplied by white_balance_shift_red/blue; the metadata says so
  // (the colour gains are 1 outside the window). -1: never.
  std::int64_t response_shift_from_frame = -1;
  std::int64_t response_shift_until_frame = -1;
  double exposure_shift_stops = 0.0;
  double white_balance_shift_red = 1.0;
  double white_balance_shift_blue = 1.0;
  // The shutter stays open for the frame's exposure time (its metadata's
  // exposure_us, a third of the 30 fps frame interval at the sensor's own
  // 10 ms) while the camera moves along its path: motion blur, centred on
  // the frame's time (sim::World::render's shutter_frames). false: each
  // frame is an instant.
  bool motion_blur = false;
  // camera.yaml's lens position, as LibcameraSettings::lens_position_dioptres:
  // the focus the source is asked to hold; nullopt: none asked.
  std::optional<double> lens_position_dioptres;
  // A lens the source can drive (LensPosition and AfMode, as the Camera
  // Module 3's, over its IMX708's range: kSimLensMaxDioptres): every frame
  // reports its position, the one asked for or else where its own autofocus
  // keeps it (lens_own_position_dioptres). false: a fixed-focus camera, whose
  // frames report none; an asked position is then a warning
  // (FrameSource::focusWarning). The picture itself stays sharp either way.
  bool lens_control = false;
  double lens_own_position_dioptres = 2.0;  // 0.5 m, about where the tag is
};

// The simulated lens's range, dioptres: libcamera's LensPosition range for
// the Camera Module 3 (IMX708), 0 (infinity) to 32.
inline constexpr double kSimLensMaxDioptres = 32.0;

class SimFrameSource : public ThreadedFrameSource {
 public:
  // Frame i has sequence i, timestamp_ns floor(i * 1e9 / 30) (30 fps), origin
  // "sim:<i>" and its truth. frame_count 0: endless. The world is shared (render() is thread-safe), so
  // tests can ask it for truth while frames are being made.
  SimFrameSource(std::shared_ptr<const sim::World> world, std::uint64_t frame_count, int pool_size = 3,
                 SimCameraOptions options = {});
  ~SimFrameSource() override;

  std::string name() const override;
  // "YUYV 640x480 (simulated)": the layout the frames come in.
  std::string streamDescription() const override;
  // The simulated camera has a fixed exposure (10 ms, gain 1, in every
  // frame's metadata): locking it changes nothing, and succeeds.
  bool lockExposure(bool locked) override;
  // The simulated sensor takes any exposure from min_exposure_us up:
  // frames are rendered log2(exposure_us * gain / 10 ms) stops from the
  // scene's exposure (sim::World::render's exposure_ev), and say so in their
  // metadata. As a camera's pipeline does, a ladder applies from a fixed
  // number of frames after the newest one handed out (the pool's size: no
  // frame from there on has been made yet), one rung a frame, so a
  // simulated run stays the same frame for frame however the threads are
  // scheduled. The simulated camera makes every frame it hands out (none is
  // dropped), so every rung arrives in order.
  bool setExposureLadder(const std::vector<ManualExposure>& per_frame) override;
  std::optional<double> shortestExposureUs() const override;
  bool takesExposureLadders() const override { return options_.exposure_controllable; }
  std::string focusWarning() const override { return focus_.warning; }

 protected:
  bool prepare(std::string& error) override;
  Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) override;
  // The exposure schedule moves on with the frames handed out.
  void handedOut(const FrameBuffer& frame) override;

 private:
  std::shared_ptr<const sim::World> world_;
  std::uint64_t frame_count_;
  SimCameraOptions options_;
  bool lost_ = false;       // the camera has gone (frame lost_at_frame failed)
  bool was_silent_ = false;  // frame silent_at_frame was held back
  bool came_back_ = false;  // ... and a restart brought it back
  int restarts_failed_ = 0;
  FocusRequest focus_;      // chosen at each start, as LibcameraSource chooses it
  ImageRGB8 rendered_;      // YUV layouts: the picture before encoding
  std::mutex exposure_mutex_;  // set on the render thread, read on the producer's
  ExposureSchedule exposure_schedule_;
};

}  // namespace probelight
