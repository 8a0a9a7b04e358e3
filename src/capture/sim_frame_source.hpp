// Frames from the simulated world, on the capture thread, with their truth.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "capture/frame_source.hpp"
#include "sim/world.hpp"

namespace probelight {

class SimFrameSource : public ThreadedFrameSource {
 public:
  // Frame i has sequence i, timestamp_ns floor(i * 1e9 / 30) (30 fps), origin
  // "sim:<i>" and its truth. frame_count 0: endless. The world is shared (render() is thread-safe), so
  // tests can ask it for truth while frames are being made.
  SimFrameSource(std::shared_ptr<const sim::World> world, std::uint64_t frame_count, int pool_size = 3);
  ~SimFrameSource() override;

  std::string name() const override;

 protected:
  Produced produce(std::uint64_t index, FrameBuffer& buffer, std::string& error) override;

 private:
  std::shared_ptr<const sim::World> world_;
  std::uint64_t frame_count_;
};

}  // namespace probelight
