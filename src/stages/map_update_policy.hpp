// When to rebuild the environment maps from the current frame, and when to
// keep the last good ones (SEEDS.md, A: pose noise moved the crop by a pixel,
// which made a new map every frame and visible flicker).
//
// Pure logic, no GL: per frame it takes what the tracker found, the ball's
// outline, the pose's rotation and the luma plane, and answers "update" (with
// the weight the new diffuse map gets against the previous one) or "skip"
// with a reason. The kiosk applies the answer; tests drive it with synthetic
// sequences.
//
// The rules, in order:
//   no tag                     -> skip "no tag"
//   outline invalid or clipped -> skip "ball not fully in view"
//   radius < min_probe_radius  -> skip "ball too small"
//   ball image almost all white -> skip "ball saturated" (see kSaturatedCode)
//   ball image almost all black -> skip "ball dark" (see kDarkCode): a cap on
//                                 the ball, a hand, lights off; a map made from
//                                 it would light the object uniformly white or
//                                 black and replace the good one
//   no maps yet                -> update (weight 1): anything beats no object
//   camera not steady          -> skip "camera moving" (a moving frame may be
//                                 blurred, and its pose lags the image)
//   fresh map requested        -> update (weight 1): start-up / recalibration
//   ball image changed         -> update (smoothed)
//   maps older than max age    -> update (smoothed): catches slow drift
//   otherwise                  -> skip "ball image unchanged"
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/probe_outline.hpp"

namespace probelight {

// probelight.yaml `map_updates:`; board/probelight.yaml documents each field.
struct MapUpdateSettings {
  // Smallest ball image worth a map: below this the 64^2 faces would mostly
  // magnify a handful of pixels.
  double min_probe_radius_px = 8.0;
  // Steadiness, between consecutive frames. What a moving camera costs is
  // motion blur and a pose that no longer matches the image, both measured
  // by how far the ball's image moves: within one exposure the smear is at
  // most the shift between frames, and one pixel is the ball image's own
  // resolution. Measured (report.json map_updates.measured): a static
  // camera's pose noise moves the outline centre 0.02 px (p95 0.04); on the
  // default orbit, where the ball really moves 0.16 px a frame, the estimate
  // moves 0.22 px (p95 0.51, max 1.15: 1 frame in 300 is called moving).
  double max_center_shift_px = 1.0;
  // The radius changes with distance; a pixel of radius change is a pixel of
  // rim motion. Measured: 0.002 px static, at most 0.09 px on the orbit.
  double max_radius_change_px = 0.5;
  // A roll about the line of sight turns the ball image without moving its
  // centre: the rim moves R * angle. 1 degree at the default ball (R ~ 30 px)
  // is 0.5 px at the rim. Measured: 0.01 degrees static; 0.25 (max 0.53)
  // on the orbit, which turns 0.2 degrees a frame. (A pan of 1 degree moves
  // the image ~10 px: the centre check catches that first.)
  double max_rotation_change_deg = 1.0;
  // Ball-image change measure (see BallSignature): mean |difference| of cell
  // means, in 8-bit luma codes. Camera noise alone gives, per cell, at most
  // 2 sigma / sqrt(pi) (two independent samples of one value; luma weights
  // and cell averaging only lower sigma): 1.7 codes at the simulator's
  // sigma = 1.5, and its mean over ~110 cells scatters by ~0.1. 3 codes is
  // above that worst case (one-pixel cells) by >10 of those deviations; at
  // the default ball (~20 pixels a cell) the floor measures 0.32 codes (max
  // 0.36); the default orbit's slow motion gives 2.7, the lamp 17.
  double change_threshold_code = 3.0;
  // A steady camera with constant light still refreshes this often, so slow
  // drift (daylight, a dimmer) is caught: 30 frames, about a second at 30
  // fps, like ARCore's environment probe (SEEDS.md).
  int max_age_frames = 30;
  // Temporal smoothing: diffuse = w * new + (1 - w) * previous on every
  // update but the first after start-up or a recalibration (w = 1 there, so
  // nothing is smoothed into black). 0.5 halves the step a pose-noise update
  // makes; a real change converges in a few frames because the policy keeps
  // updating until the blended reference matches the image (see below).
  double smoothing_new_weight = 0.5;
};

enum class MapSkipReason {
  kNone,
  kNoTag,
  kBallNotInView,
  kBallTooSmall,
  kBallSaturated,
  kBallDark,
  kCameraMoving,
  kImageUnchanged
};
// The report's words: "no tag", "ball not fully in view", "ball too small",
// "ball saturated", "ball dark", "camera moving", "ball image unchanged"; ""
// for kNone.
const char* toString(MapSkipReason reason);

enum class MapUpdateCause { kNone, kFirst, kFreshRequested, kImageChanged, kMaxAge };
// "first", "fresh requested", "image changed", "max age"; "" for kNone.
const char* toString(MapUpdateCause cause);

// A cheap summary of the ball's image: the square [c - 0.9 r, c + 0.9 r]^2
// cut into kCells x kCells cells; each cell holds the mean luma of the pixels
// (centres at integers) that lie in it and within 0.9 r of the centre. The
// outer 10% is left out: there the rim squeezes half the world into a thin
// ring and the outline's sub-pixel error mixes in the background. Cell means
// cover every pixel, so a small bright change (a lamp's image a few pixels
// wide) counts with its full area, which a sparse point grid could miss.
struct BallSignature {
  static constexpr int kCells = 12;
  static constexpr double kExtent = 0.9;  // of the radius
  glm::dvec2 center_px{0.0};
  double radius_px = 0.0;
  std::vector<float> mean;   // kCells^2, row-major
  std::vector<int> count;    // pixels per cell; 0: no pixel (cell off the disc or image)
  bool empty() const { return mean.empty(); }
};

BallSignature sampleBallSignature(const LumaView& luma, glm::dvec2 center_px, double radius_px);

// Unusable ball images, judged on the signature's cell means (8-bit luma
// codes), from the format and the noise alone, not from any scene:
// - A clipped pixel reads 255. Noise added before the clip (sensor noise,
//   sigma codes) pulls a clipped cell's mean down to E[min(255, 255 + n)] =
//   255 - sigma / sqrt(2 pi) = 255 - 0.40 sigma; 250 leaves 5 codes, i.e. it
//   still calls a clipped cell clipped at sigma up to 12 codes (8x the
//   simulator's 1.5, well above a usable camera's). A cell above 250 that is
//   not clipped carries at most 5 codes (2%) of information before white.
// - Black is the mirror case at code 0: E[max(0, n)] = 0.40 sigma, so <= 5
//   codes holds to sigma 12 too. Code 5 is sRGB-linear 0.0015 of white, where
//   one code step is a 20% change: no lighting can be read from it.
// - 95% of the cells (the disc has ~110 of the 144): a real room image of the
//   ball always has some structure, but a cap, a hand or a blown-out frame
//   may leave a rim of a few cells (5% is ~5 cells) that still show something;
//   such a frame is still useless. Below 95% the image holds enough
//   directions that the map is worth more than the old one.
inline constexpr double kSaturatedCode = 250.0;
inline constexpr double kDarkCode = 5.0;
inline constexpr double kUnusableCellFraction = 0.95;

// Which share of the signature's cells (those holding pixels) is >= kSaturatedCode
// and which is <= kDarkCode; both 0 for an empty signature.
struct BallExposure {
  double saturated_fraction = 0.0;
  double dark_fraction = 0.0;
  int cells = 0;
};
BallExposure measureBallExposure(const BallSignature& signature);

// Mean |a - b| over the cells both hold, in codes; nullopt when none.
std::optional<double> signatureDifference(const BallSignature& a, const BallSignature& b);

struct MapFrameInput {
  bool tag_found = false;
  ibl::ProbeOutline outline;              // meaningful when tag_found
  glm::dmat3 rotation_cam_from_world{1.0};  // the pose's rotation, when tag_found
  LumaView luma;
};

struct MapUpdateDecision {
  bool update = false;
  MapSkipReason skip = MapSkipReason::kNone;
  MapUpdateCause cause = MapUpdateCause::kNone;
  float new_weight = 1.0f;  // for the diffuse blend: 1 replaces the previous map
  // What the policy measured this frame (for the report); unset where it did
  // not get that far.
  std::optional<double> center_shift_px;
  std::optional<double> radius_change_px;
  std::optional<double> rotation_change_deg;
  std::optional<double> image_change_code;  // against the reference (see class comment)
  std::optional<double> saturated_fraction;  // of the ball's cells, when the ball was usable so far
  std::optional<double> dark_fraction;
};

// One per kiosk. decide() assumes the caller applies an "update" answer.
//
// The change measure compares the current frame with a reference signature
// sampled on the reference's own grid (the outline of the last update), not
// on this frame's outline: while the camera is steady the ball's pixels stay
// where they were, so pose noise moving the outline by a few tenths of a
// pixel cannot look like a change (it would, at every sharp edge of the ball
// image, and bring back the flicker). Real motion slides the image under the
// grid and is seen.
// With smoothing the reference is blended like the diffuse map
// (w * new + (1 - w) * reference), so it stands for what the map holds: after
// a lamp switches on, the image keeps differing from the reference, and the
// policy keeps updating, until the map has converged.
class MapUpdatePolicy {
 public:
  explicit MapUpdatePolicy(MapUpdateSettings settings = {});

  MapUpdateDecision decide(const MapFrameInput& frame);
  // The next frame that may update does, with weight 1, even when its image
  // is unchanged (a recalibration must fit a fresh map).
  void requestFreshMap() { fresh_requested_ = true; }

  bool haveMaps() const { return have_maps_; }
  int framesSinceUpdate() const { return frames_since_update_; }
  const MapUpdateSettings& settings() const { return settings_; }

 private:
  struct PreviousFrame {
    glm::dvec2 center_px;
    double radius_px;
    glm::dmat3 rotation;
  };

  MapUpdateSettings settings_;
  std::optional<PreviousFrame> previous_;  // the last frame with a valid outline, if it was the one before
  BallSignature reference_;
  bool have_maps_ = false;
  bool fresh_requested_ = false;
  int frames_since_update_ = 0;
};

}  // namespace probelight
