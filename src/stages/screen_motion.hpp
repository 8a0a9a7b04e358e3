// How fast the object's image moves across the frame (issue 19's motion
// blur): from the tracked poses of the last frames, the on-screen velocity
// of one point (the object's centre) at the newest frame, and the smear it
// draws while the shutter is open.
//
// The velocity is the derivative at the newest frame of the parabola
// through the last three positions (a second-order backward difference,
// for frames unevenly spaced in time too): exact for a steady
// acceleration, where the two-frame difference trails by half a frame's
// change of speed (a turn of a hand-held pan). With two positions it is
// their difference. A frame's pose is where the tag's image sits, and a
// smeared tag's image sits at the middle of its smear: the velocity there
// times the exposure time is the smear, centred on the drawn object.
//
// Pure: no GL, no clock; times come from the frames' timestamps.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

namespace probelight {

class ScreenMotion {
 public:
  // Positions further apart in time than this are not one motion (frames
  // lost, the tag found again): the history starts again.
  static constexpr double kLongestGapS = 0.25;

  // A tracked frame's position of the point (px) at time_s. A time not
  // after the last one, a gap over kLongestGapS or a non-finite input
  // starts the history again (from this position when it is finite).
  void observe(double time_s, const glm::dvec2& position_px);
  // The point is not in view (no tag): the motion is not known.
  void forget() { samples_.clear(); }

  // px/s at the newest position; none with fewer than two.
  std::optional<glm::dvec2> velocityPxPerS() const;
  // The path drawn over an exposure of exposure_s (velocity x time, px),
  // centred on the newest position; none when the velocity is unknown or
  // the exposure not positive and finite.
  std::optional<glm::dvec2> smearPx(double exposure_s) const;

 private:
  struct Sample {
    double time_s;
    glm::dvec2 position_px;
  };
  std::vector<Sample> samples_;  // the last three at most, oldest first
};

}  // namespace probelight
