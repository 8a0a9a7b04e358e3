// The probe merged over the views the camera passes through
// (ibl/probe_accumulator.hpp): each view's reflection map, and the frame
// around its ball (ibl/probe_observation.hpp), in the maps' units (camera
// linear / reflectance) at the probe's exposure. The kiosk's maps stage
// merges every map update into it and shows the merged probe; a
// recalibration's bracket goes into it too, so that the fit sees every
// view's light and the bracket's measured highlights. `analyze` merges its
// --frame views the same way.
//
// Exposure: camera-linear values scale with exposure time x gain. The probe
// holds one exposure's units; a view in another is scaled to it, and the
// kiosk moves the whole probe to each new frame's exposure (followExposure),
// so that its maps stay in the frame's units as a single view's are.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "capture/frame_source.hpp"
#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_accumulator.hpp"
#include "ibl/probe_observation.hpp"

namespace probelight {

struct ProbeViewCounts {
  ibl::AccumulateCounts merge;
  long texels_from_frame_around_ball = 0;
};

class ProbeMerge {
 public:
  ProbeMerge(const ibl::CameraTransfer& camera_transfer, const RigGeometry& rig, int face_size,
             const ibl::ObservationSettings& observation = {});

  // The largest value an 8-bit frame measures, in map units at the view's
  // own exposure (ibl::clippedMapLevel).
  double clipLevel() const { return clip_level_; }

  // One view into the probe. `map` its reflection map and `validity` the
  // map's alpha (null: the texels the view's ball shows), `still_clipped` a
  // bracket's flags (given: the view is a bracket's; null: an 8-bit view,
  // whose texel is a lower bound where a channel reaches the clip level,
  // and, below a bracket's measurement, where it read beside a clipped
  // pixel of `frame` or near the rim), `to_probe_exposure` what turns the
  // view's units into the probe's (the probe's exposure / the view's).
  // With `frame`, the pixels around the ball fill what it hides.
  ProbeViewCounts addView(const ibl::MirrorBallView& view, const ibl::CubeMapRGB& map, const std::vector<float>* validity,
                          const std::vector<std::uint8_t>* still_clipped, double to_probe_exposure,
                          const FrameBuffer* frame);

  // The probe's exposure (time x gain) becomes `exposure_product`, its
  // radiance scaled with it. The first known exposure only names the units.
  // Not finite or <= 0: the source cannot say; nothing changes.
  void followExposure(double exposure_product);
  // 0 until an exposure is known.
  double exposure() const { return exposure_product_; }
  // The same for the white balance's red and blue gains (0: unknown), per
  // channel: the probe's red and blue follow each frame's.
  void followWhiteBalance(double red_gain, double blue_gain);
  // What a view at `exposure_product` is multiplied by to be in the probe's
  // units (1 when either is unknown).
  double toProbeExposure(double exposure_product) const;

  bool empty() const { return accumulator_.empty(); }
  // The live maps' reflection: each channel at most the clip level (what the
  // 8-bit frames show; the rest is the clipped lights', fitted apart).
  // `clip_scale`: the clip level of the frame the clipped lights were
  // fitted in, in the probe's units now (stages/frame_response.hpp): the
  // clipped lights carry what was above it, scaled with the exposure, so
  // the map holds what was below it, scaled alike, and the two still add
  // up to the light after auto exposure moved.
  ibl::CubeMapRGB liveMap(const glm::vec3& clip_scale = glm::vec3(1.0f)) const {
    return accumulator_.radianceMap(static_cast<float>(clip_level_) * clip_scale);
  }
  // The whole measured radiance, brackets' highlights included.
  ibl::CubeMapRGB hdrMap() const { return accumulator_.radianceMap(); }
  std::vector<float> validity() const { return accumulator_.validity(); }
  // Some texel holds more than an 8-bit frame shows (a bracket measured it):
  // the light fit has an HDR map.
  bool holdsAboveClip() const;
  // The irradiance (luminance) of the live map at the six axis normals
  // (+x, +y, +z, -x, -y, -z): what tells whether the diffuse map made from
  // it would change.
  std::array<double, 6> axisIrradiance() const;
  const ibl::ProbeAccumulator& accumulator() const { return accumulator_; }
  // Per texel, 1 where a bracket that knew the texel's direction only to
  // more than a texel (confidence 1 / sigma^2: it saw it in the ball's rim,
  // where it smears a sun over several texels) measured it, and an 8-bit
  // view that knows the direction at least as well replaced that
  // measurement: what the bracket smeared over the texel is elsewhere.
  // Cleared where a bracket measures the texel again. What the
  // clipped-light follower leaves out of a light
  // (ClippedLightFollower::sharesFor). A bracket that saw the texel sharply
  // cannot have smeared a light over it: a change there is the light's.
  std::vector<std::uint8_t> texelsResolvedBySharperViews() const;

  // A saved probe (stages/state_store): false, nothing changed, when it
  // does not fit this probe (face size, values).
  bool restore(const std::vector<glm::vec4>& texels, double exposure_product, std::string& error);

 private:
  void markTexelsTouchingClippedPixels(const ibl::MirrorBallView& view, const FrameBuffer& frame,
                                       double to_probe_exposure);
  void markMeasuredTexelsWithAClippedPixelInTheirFootprint(const ibl::MirrorBallView& view, const FrameBuffer& frame,
                                                          double to_probe_exposure);
  // The kept estimate of `texel` is a measurement (not a bound) above what
  // an 8-bit frame shows.
  bool measuredAboveClip(std::size_t texel) const;
  // After each view: which texels hold a bracket's measurement (set by a
  // bracket, cleared where a later sample replaced it).
  void trackBracketTexels(bool bracket);
  void boundWhereLessSureThanTheBracket(double to_probe_exposure);

  ibl::CameraTransfer camera_transfer_;
  RigGeometry rig_;
  ibl::ObservationSettings observation_settings_;
  double clip_level_;
  std::uint8_t clip_code_;
  ibl::ProbeAccumulator accumulator_;
  ibl::ProbeObservation observation_;  // kept from view to view
  std::vector<std::uint8_t> touched_by_clipped_;  // ... and the texels a clipped pixel reaches
  std::vector<std::uint8_t> near_clipped_pixels_;  // ... from these pixels
  // How sure the bracket whose measurement a texel holds was of its
  // direction (0: the texel holds no bracket's measurement;
  // kResolvedBySharperView: a sharper view replaced it).
  static constexpr float kResolvedBySharperView = -1.0f;
  std::vector<float> bracket_confidence_;
  double exposure_product_ = 0.0;
  double red_gain_ = 0.0, blue_gain_ = 0.0;
};

}  // namespace probelight
