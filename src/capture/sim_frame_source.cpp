#include "capture/sim_frame_source.hpp"

#include <exception>

namespace probelight {

SimFrameSource::SimFrameSource(std::shared_ptr<const sim::World> world, std::uint64_t frame_count, int pool_size)
    : ThreadedFrameSource(pool_size), world_(std::move(world)), frame_count_(frame_count) {}

SimFrameSource::~SimFrameSource() {
  // produce() uses our members: stop the thread before they are destroyed.
  stop();
}

std::string SimFrameSource::name() const { return "sim:" + world_->scene().environment; }

ThreadedFrameSource::Produced SimFrameSource::produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) {
  if (frame_count_ != 0 && index >= frame_count_) return Produced::kEndOfStream;
  try {
    FrameTruth truth;
    world_->render(index, buffer.rgb, truth);
    buffer.metadata = FrameMetadata{};
    buffer.metadata.sequence = index;
    // Exact 30 fps without drift: index * 1e9 / 30, rounded down.
    buffer.metadata.timestamp_ns = static_cast<std::int64_t>(index * 1'000'000'000ull / 30u);
    buffer.metadata.origin = "sim:" + std::to_string(index);
    buffer.metadata.truth = truth;
  } catch (const std::exception& e) {
    error = "sim frame " + std::to_string(index) + ": " + e.what();
    return Produced::kError;
  }
  return Produced::kFrame;
}

}  // namespace probelight
