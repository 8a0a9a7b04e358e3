// The camera's motion through an exposure bracket, as a pure unit.
//
// A kiosk's bracket is a handful of consecutive frames, each shorter than
// the one before. The tag gives the pose of the brighter ones; in the
// darkest (the ones that measure a sun or a lamp) it is too dark to find.
// A camera held still leaves those where the reference frame was; a
// hand-held camera that moves on (a sweep at 12 degrees a second moves the
// ball 0.35 px a frame at 0.55 m) does not, and a frame merged with a pose
// a pixel off misplaces the very light it measures. So the poses the tag
// gave are fitted with one constant velocity through the reference frame's
// pose (the brightest, whose tag is surest), and a frame without a pose
// takes the fitted one at its time.
//
// Rotation as a rotation vector relative to the reference, and the
// camera's centre in the world: for the small motions of a bracket (tenths
// of a second) both are linear in time to far better than the tag's pose.
#pragma once

#include <optional>
#include <vector>

#include "core/types.hpp"

namespace probelight {

class BracketMotion {
 public:
  // The reference frame's pose and time (seconds, any origin). A time that
  // is not finite: no motion can be fitted (frames from files).
  BracketMotion(const PoseCamFromWorld& reference, double reference_time_s);

  // A later frame whose tag gave its pose. Ignored when either time is not
  // finite, or when it is the reference's time.
  void addTracked(double time_s, const PoseCamFromWorld& pose);

  // The pose at `time_s` by the least-squares velocity through the
  // reference; nullopt without a tracked frame or a finite time.
  std::optional<PoseCamFromWorld> poseAt(double time_s) const;

  int trackedCount() const { return static_cast<int>(samples_.size()); }

 private:
  struct Sample {
    double dt_s;
    glm::dvec3 rotation_vector;  // of R * R_reference^T
    glm::dvec3 centre_shift_w;   // camera centre minus the reference's
  };
  PoseCamFromWorld reference_;
  double reference_time_s_;
  std::vector<Sample> samples_;
};

}  // namespace probelight
