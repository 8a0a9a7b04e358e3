#include "capture/sim_frame_source.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

#include "sim/camera_ycbcr.hpp"

namespace probelight {

void encodeSimFrame(const ImageRGB8& rgb, PixelLayout layout, FrameBuffer& frame) {
  const YcbcrEncoding sycc{YcbcrMatrix::kRec601, true};
  if (layout == PixelLayout::kRgb8) {
    frame.rgb = rgb;
    frame.finishRgb();
    return;
  }
  if (isPacked(layout)) {
    FramePlanes& planes = frame.allocatePacked(layout, rgb.width, rgb.height, sycc);
    auto* plane = const_cast<std::uint8_t*>(planes.data[0]);
    if (layout == PixelLayout::kYuyv) {
      sim::encodeYcbcr422Sycc(rgb, plane, planes.stride_bytes[0]);
    } else {
      // The camera's byte order, written here from the format's definition
      // (DRM's little-endian words: RGB888 is B, G, R in memory).
      const bool blue_first = layout != PixelLayout::kBgr888;
      const int step = layout == PixelLayout::kXrgb8888 ? 4 : 3;
      for (int y = 0; y < rgb.height; ++y)
        for (int x = 0; x < rgb.width; ++x) {
          const std::uint8_t* in = rgb.row(y) + 3 * x;
          std::uint8_t* out = plane + static_cast<std::size_t>(y) * planes.stride_bytes[0] + step * x;
          out[0] = blue_first ? in[2] : in[0];
          out[1] = in[1];
          out[2] = blue_first ? in[0] : in[2];
          if (step == 4) out[3] = 0xFF;
        }
    }
    frame.finishPacked();
    return;
  }
  FramePlanes& planes = frame.allocateYuv420(layout, rgb.width, rgb.height, sycc);
  auto* luma = const_cast<std::uint8_t*>(planes.data[0]);
  auto* cb = const_cast<std::uint8_t*>(planes.data[1]);
  if (layout == PixelLayout::kNv12)
    sim::encodeYcbcr420Sycc(rgb, luma, planes.stride_bytes[0], cb, cb + 1, planes.stride_bytes[1], 2);
  else
    sim::encodeYcbcr420Sycc(rgb, luma, planes.stride_bytes[0], cb, const_cast<std::uint8_t*>(planes.data[2]),
                            planes.stride_bytes[1], 1);
}

SimFrameSource::SimFrameSource(std::shared_ptr<const sim::World> world, std::uint64_t frame_count, int pool_size,
                               SimCameraOptions options)
    : ThreadedFrameSource(pool_size),
      world_(std::move(world)),
      frame_count_(frame_count),
      options_(options),
      exposure_schedule_(pool_size) {}

bool SimFrameSource::lockExposure(bool locked) {
  (void)locked;
  return true;
}

bool SimFrameSource::setExposureLadder(const std::vector<ManualExposure>& per_frame) {
  if (!per_frame.empty() && !options_.exposure_controllable) return false;
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  exposure_schedule_.request(per_frame);
  return true;
}

std::optional<double> SimFrameSource::shortestExposureUs() const {
  if (options_.min_exposure_us > 0.0 && options_.min_exposure_reported) return options_.min_exposure_us;
  return std::nullopt;
}

void SimFrameSource::handedOut(const FrameBuffer& frame) {
  std::lock_guard<std::mutex> lock(exposure_mutex_);
  exposure_schedule_.handedOut(frame.metadata.sequence);
}

bool SimFrameSource::prepare(std::string& error) {
  if (lost_ && !came_back_) {
    if (restarts_failed_ < options_.failed_restarts) {
      ++restarts_failed_;
      error = "camera: sim camera unplugged (no camera found)";
      return false;
    }
    came_back_ = true;
  }
  // Before the producer's thread starts, which reads it.
  LensControlsOffered offered;
  if (options_.lens_control) offered = {true, true, 0.0, kSimLensMaxDioptres};
  focus_ = chooseFocusRequest(options_.lens_position_dioptres, offered, name());
  return true;
}

SimFrameSource::~SimFrameSource() {
  // produce() uses our members: stop the thread before they are destroyed.
  stop();
}

std::string SimFrameSource::name() const { return "sim:" + world_->scene().environment; }

std::string SimFrameSource::streamDescription() const {
  const CameraIntrinsics& camera = world_->scene().camera;
  return std::string(layoutName(options_.layout)) + " " + std::to_string(camera.width_px) + "x" +
         std::to_string(camera.height_px) + " (simulated)";
}

ThreadedFrameSource::Produced SimFrameSource::produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) {
  if (frame_count_ != 0 && index >= frame_count_) return Produced::kEndOfStream;
  if (options_.lost_at_frame >= 0 && index == static_cast<std::uint64_t>(options_.lost_at_frame) && !lost_) {
    lost_ = true;
    error = "camera: sim camera disconnected";
    return Produced::kError;
  }
  if (options_.silent_at_frame >= 0 && index == static_cast<std::uint64_t>(options_.silent_at_frame) &&
      !was_silent_) {
    was_silent_ = true;
    const auto silence = std::chrono::milliseconds(static_cast<long long>(1000.0 * options_.silent_s));
    if (!pauseUnlessStopped(silence)) return Produced::kEndOfStream;  // stopped while silent
  }
  // The sensor's own exposure: 10 ms at gain 1 (the scene's exposure),
  // shifted by exposure_stops.
  constexpr double kSimExposureUs = 10000.0;
  const bool shifted = options_.response_shift_from_frame >= 0 &&
                       index >= static_cast<std::uint64_t>(options_.response_shift_from_frame) &&
                       (options_.response_shift_until_frame < 0 ||
                        index < static_cast<std::uint64_t>(options_.response_shift_until_frame));
  const double own_stops = options_.exposure_stops + (shifted ? options_.exposure_shift_stops : 0.0);
  ManualExposure exposure{kSimExposureUs * std::exp2(own_stops), 1.0};
  // A bracket's frames keep the white balance (AWB is locked with AE).
  glm::dvec3 white_balance(1.0);
  if (shifted) white_balance = {options_.white_balance_shift_red, 1.0, options_.white_balance_shift_blue};
  {
    std::lock_guard<std::mutex> lock(exposure_mutex_);
    if (const auto scheduled = exposure_schedule_.at(index)) exposure = *scheduled;
  }
  exposure.exposure_us = std::max(exposure.exposure_us, options_.min_exposure_us);
  const double exposure_ev = std::log2(exposure.exposure_us * exposure.analogue_gain / kSimExposureUs);
  constexpr double kFrameIntervalUs = 1e6 / 30.0;
  const double shutter_frames = options_.motion_blur ? exposure.exposure_us / kFrameIntervalUs : 0.0;
  try {
    FrameTruth truth;
    if (options_.layout != PixelLayout::kRgb8) {
      world_->render(index, rendered_, truth, exposure_ev, white_balance, shutter_frames);
      encodeSimFrame(rendered_, options_.layout, buffer);
    } else {
      world_->render(index, buffer.rgb, truth, exposure_ev, white_balance, shutter_frames);
      buffer.finishRgb();
    }
    buffer.metadata = FrameMetadata{};
    buffer.metadata.sequence = index;
    // Exact 30 fps without drift: index * 1e9 / 30, rounded down.
    buffer.metadata.timestamp_ns = static_cast<std::int64_t>(index * 1'000'000'000ull / 30u);
    buffer.metadata.origin = "sim:" + std::to_string(index);
    buffer.metadata.exposure_us = exposure.exposure_us;
    buffer.metadata.analogue_gain = exposure.analogue_gain;
    buffer.metadata.red_gain = white_balance.r;
    buffer.metadata.blue_gain = white_balance.b;
    if (options_.lens_control)
      buffer.metadata.lens_position_dioptres = focus_.lens_position_dioptres.value_or(options_.lens_own_position_dioptres);
    buffer.metadata.truth = truth;
  } catch (const std::exception& e) {
    error = "sim frame " + std::to_string(index) + ": " + e.what();
    return Produced::kError;
  }
  return Produced::kFrame;
}

}  // namespace probelight
