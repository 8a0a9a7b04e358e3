// Optional temporal smoothing of the tracked pose, without lag on real motion.
//
// A One Euro filter (Casiez, Roussel & Vogel, CHI 2012): a first-order
// low-pass whose cutoff rises with the speed of the motion,
//   f_c = static_cutoff_hz + beta * speed,
// so a still camera is smoothed hard and a moving one hardly at all. Speed is
// measured where it matters, on screen: the image velocity (px/s) of a few
// reference points (the tag's corners and the ball's centre), low-passed as
// signed 2-D vectors, so that noise, which has no direction, averages out of
// it instead of opening the filter; the speed is the largest of their lengths.
//
// beta is not a tuning constant: a first-order filter at cutoff f_c trails a
// motion of speed v by v / (2 pi f_c), which for large v tends to
// 1 / (2 pi beta) pixels. So the setting is that bound, max_lag_px, and
// beta = 1 / (2 pi max_lag_px): however fast the camera moves, the smoothed
// pose stays within about max_lag_px of where the raw one draws things (the
// speed estimate itself is low-passed, so the first frames of a sudden start
// lag a little more).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::tracking {

struct PoseSmoothingSettings {
  bool enabled = true;
  double static_cutoff_hz = 1.0;      // cutoff for a still camera: noise falls ~3x at 30 fps
  double max_lag_px = 0.1;            // bound on the on-screen lag at any speed (sets beta)
  double speed_cutoff_hz = 1.0;       // low-pass on the speed estimate, so noise does not open the filter
  double reset_jump_px = 40.0;        // a larger jump in one frame is a new view (re-acquired tag): no smoothing across it
};

class PoseSmoother {
 public:
  // `reference_points_w`: world points whose image motion defines speed and
  // lag. Throws std::invalid_argument for non-positive or non-finite settings
  // or no reference points.
  PoseSmoother(PoseSmoothingSettings settings, CameraIntrinsics camera, std::vector<glm::dvec3> reference_points_w);

  // The smoothed pose for a raw pose measured at `timestamp_s`. With
  // smoothing disabled, or on the first call, after reset(), a time step
  // that is not positive or longer than a second, or a jump over
  // reset_jump_px, returns `raw` and restarts from it.
  PoseCamFromWorld update(const PoseCamFromWorld& raw, double timestamp_s);
  void reset() { state_.reset(); }

  // Of the last update: the filtered on-screen speed (px/s) and the cutoff used.
  double speedPxPerS() const { return state_ ? state_->speed_px_per_s : 0.0; }
  double cutoffHz() const { return last_cutoff_hz_; }
  const PoseSmoothingSettings& settings() const { return settings_; }

  // Image displacement (px, pinhole) of each reference point from pose a to
  // pose b; zero for a point behind either camera.
  std::vector<glm::dvec2> imageDisplacementsPx(const PoseCamFromWorld& a, const PoseCamFromWorld& b) const;
  // The largest of their lengths.
  double largestDisplacementPx(const PoseCamFromWorld& a, const PoseCamFromWorld& b) const;

 private:
  struct State {
    PoseCamFromWorld pose;      // the last output
    PoseCamFromWorld raw_pose;  // the last input
    double timestamp_s = 0.0;
    std::vector<glm::dvec2> velocity_px_per_s;  // per reference point, low-passed
    double speed_px_per_s = 0.0;                 // the largest filtered velocity's length
  };
  PoseSmoothingSettings settings_;
  CameraIntrinsics camera_;
  std::vector<glm::dvec3> reference_points_w_;
  std::optional<State> state_;
  double last_cutoff_hz_ = 0.0;
};

// The points whose on-screen motion matters for a rig: the tag's four
// corners and the ball's centre.
std::vector<glm::dvec3> smoothingReferencePoints(const RigGeometry& rig);

// Mixing weight of a first-order low-pass at cutoff_hz over a step dt_s:
// 1 / (1 + 1 / (2 pi cutoff dt)).
double lowPassWeight(double cutoff_hz, double dt_s);

}  // namespace probelight::tracking
