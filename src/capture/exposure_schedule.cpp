#include "capture/exposure_schedule.hpp"

namespace probelight {

void ExposureSchedule::request(const std::vector<ManualExposure>& per_frame) {
  // The consumer holds the newest frame; the pool's other buffers may hold
  // the next ones already made. From newest + pool size on, none is: the
  // ladder starts there, and replaces what was to come from there on.
  const std::uint64_t first = newest_handed_out_ + static_cast<std::uint64_t>(frames_ahead_);
  while (!changes_.empty() && changes_.back().first >= first) changes_.pop_back();
  // Of the changes every frame still to come is past, only the newest is
  // needed (an endless run recalibrates again and again).
  std::size_t first_needed = 0;
  for (std::size_t i = 0; i < changes_.size(); ++i)
    if (changes_[i].first <= newest_handed_out_) first_needed = i;
  changes_.erase(changes_.begin(), changes_.begin() + static_cast<std::ptrdiff_t>(first_needed));
  if (per_frame.empty()) {
    changes_.emplace_back(first, std::nullopt);
    return;
  }
  for (std::size_t i = 0; i < per_frame.size(); ++i) changes_.emplace_back(first + i, per_frame[i]);
}

std::optional<ExposureSchedule::ManualExposure> ExposureSchedule::at(std::uint64_t index) const {
  std::optional<ManualExposure> exposure;
  for (const auto& [from_index, change] : changes_)
    if (from_index <= index) exposure = change;
  return exposure;
}

void ExposureSchedule::clear() {
  changes_.clear();
  newest_handed_out_ = 0;
}

}  // namespace probelight
