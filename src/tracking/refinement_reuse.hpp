// When the tag has not moved, the last frame's corner refinement and pose
// polish still hold: keep them, and skip both (about 3 of the 5 ms
// detect_pose takes on the desktop).
//
// "Not moved" is judged on the detector's own corners (libapriltag's, before
// refinement), which every frame has anyway: each of the four within
// max_shift_px of where they were in the frame that was last refined. They
// jitter by a few hundredths of a pixel on a still camera with sensor noise,
// so a still view reuses; a camera moving by more than max_shift_px in all
// (not a frame) since that refinement refines again. The shift is measured
// from the refined frame, not the previous one, so a slow drift cannot pile
// up unnoticed: the pose trails the tag by at most max_shift_px on screen
// plus the corners' noise, which is why the default is the pose smoother's
// own lag budget (tracking.smoothing.max_lag_px, 0.1 px). At most
// max_frames frames reuse one refinement, so one made on a bad frame (blur,
// a passing shadow) does not stay for good.
#pragma once

#include <array>
#include <optional>
#include <utility>

#include <glm/glm.hpp>

namespace probelight::tracking {

struct RefinementReuseSettings {
  double max_shift_px = 0.1;  // 0: refine every frame
  int max_frames = 30;
};

// Keeps what a refinement produced (`Refined`: for TagTracker the refined
// corners and the polished planar solutions) with the detector corners it
// was made from.
template <typename Refined>
class RefinementReuse {
 public:
  explicit RefinementReuse(RefinementReuseSettings settings = {}) : settings_(settings) {}

  // The stored refinement, when tag `id`'s detector corners are each within
  // max_shift_px of those it was made from and it has been reused fewer
  // than max_frames times; counts the reuse. Null otherwise (refine, then
  // store()).
  const Refined* reuse(int id, const std::array<glm::dvec2, 4>& detector_corners_px) {
    if (!stored_ || stored_->id != id || !(settings_.max_shift_px > 0.0) ||
        stored_->reused_frames >= settings_.max_frames)
      return nullptr;
    for (std::size_t k = 0; k < 4; ++k)
      if (!(glm::length(detector_corners_px[k] - stored_->detector_corners_px[k]) <= settings_.max_shift_px))
        return nullptr;
    ++stored_->reused_frames;
    return &stored_->refined;
  }

  // A new refinement of tag `id` from these detector corners.
  void store(int id, const std::array<glm::dvec2, 4>& detector_corners_px, Refined refined) {
    stored_ = Stored{id, detector_corners_px, std::move(refined), 0};
  }

  // Forget it (the tag was lost, a refinement failed, the history was reset).
  void clear() { stored_.reset(); }

 private:
  struct Stored {
    int id = -1;
    std::array<glm::dvec2, 4> detector_corners_px{};
    Refined refined;
    int reused_frames = 0;
  };
  RefinementReuseSettings settings_;
  std::optional<Stored> stored_;
};

}  // namespace probelight::tracking
