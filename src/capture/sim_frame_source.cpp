#include "capture/sim_frame_source.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

#include "sim/camera_ycbcr.hpp"

namespace probelight {

void encodeSimFrame(const ImageRGB8& rgb, PixelLayout layout, FrameBuffer& frame) {
  if (!isYuv(layout)) {
    frame.rgb = rgb;
    frame.finishRgb();
    return;
  }
  YuvPlanes& planes = frame.allocateYuv420(layout, rgb.width, rgb.height, YcbcrEncoding{YcbcrMatrix::kRec601, true});
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
  return true;
}

SimFrameSource::~SimFrameSource() {
  // produce() uses our members: stop the thread before they are destroyed.
  stop();
}

std::string SimFrameSource::name() const { return "sim:" + world_->scene().environment; }

ThreadedFrameSource::Produced SimFrameSource::produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) {
  if (frame_count_ != 0 && index >= frame_count_) return Produced::kEndOfStream;
  if (options_.lost_at_frame >= 0 && index == static_cast<std::uint64_t>(options_.lost_at_frame) && !lost_) {
    lost_ = true;
    error = "camera: sim camera disconnected";
    return Produced::kError;
  }
  // The sensor's own exposure: 10 ms at gain 1 (the scene's exposure),
  // shifted by exposure_stops.
  constexpr double kSimExposureUs = 10000.0;
  ManualExposure exposure{kSimExposureUs * std::exp2(options_.exposure_stops), 1.0};
  {
    std::lock_guard<std::mutex> lock(exposure_mutex_);
    if (const auto scheduled = exposure_schedule_.at(index)) exposure = *scheduled;
  }
  exposure.exposure_us = std::max(exposure.exposure_us, options_.min_exposure_us);
  const double exposure_ev = std::log2(exposure.exposure_us * exposure.analogue_gain / kSimExposureUs);
  try {
    FrameTruth truth;
    if (isYuv(options_.layout)) {
      world_->render(index, rendered_, truth, exposure_ev);
      encodeSimFrame(rendered_, options_.layout, buffer);
    } else {
      world_->render(index, buffer.rgb, truth, exposure_ev);
      buffer.finishRgb();
    }
    buffer.metadata = FrameMetadata{};
    buffer.metadata.sequence = index;
    // Exact 30 fps without drift: index * 1e9 / 30, rounded down.
    buffer.metadata.timestamp_ns = static_cast<std::int64_t>(index * 1'000'000'000ull / 30u);
    buffer.metadata.origin = "sim:" + std::to_string(index);
    buffer.metadata.exposure_us = exposure.exposure_us;
    buffer.metadata.analogue_gain = exposure.analogue_gain;
    buffer.metadata.truth = truth;
  } catch (const std::exception& e) {
    error = "sim frame " + std::to_string(index) + ": " + e.what();
    return Produced::kError;
  }
  return Produced::kFrame;
}

}  // namespace probelight
