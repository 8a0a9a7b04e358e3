// Which exposure each frame a source makes is taken at, from the ladders the
// pipeline asks for (ExposureControl::setExposureLadder). A source that
// makes frames ahead (a pool of buffers) cannot change the frames already
// made: a ladder starts after them, at the consumer's newest frame plus the
// pool's size, and replaces whatever was scheduled from there on. One job,
// no locking (the source holds its own lock around it).
#pragma once

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "capture/exposure_control.hpp"

namespace probelight {

class ExposureSchedule {
 public:
  using ManualExposure = ExposureControl::ManualExposure;

  explicit ExposureSchedule(int frames_ahead) : frames_ahead_(frames_ahead) {}

  // One exposure per frame from the first frame not yet made; an empty
  // ladder goes back to the source's own exposure there.
  void request(const std::vector<ManualExposure>& per_frame);
  // The consumer now holds frame `index` (frames arrive in order).
  void handedOut(std::uint64_t index) { newest_handed_out_ = index; }
  // The exposure frame `index` is to be taken at; nullopt: the source's own.
  std::optional<ManualExposure> at(std::uint64_t index) const;
  // A restarted stream numbers its frames from 0 again.
  void clear();

 private:
  int frames_ahead_;
  std::uint64_t newest_handed_out_ = 0;
  // From which frame index each change applies (increasing).
  std::vector<std::pair<std::uint64_t, std::optional<ManualExposure>>> changes_;
};

}  // namespace probelight
