// An exposure bracket (the same view at several exposures) merged into one
// linear radiance image, as seed-style HDR capture does: each 8-bit value is
// decoded through the camera transfer, divided by its frame's exposure
// ratio, and averaged with a weight for how well exposed it is. Values the
// camera clipped (or drowned in noise) get no weight, so each pixel's
// radiance comes from the frames that measured it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"

namespace probelight::ibl {

struct BracketFrame {
  const ImageRGB8* image = nullptr;
  // Stops from the reference exposure (0 for the reference itself, -3 for a
  // frame exposed 8x shorter).
  double ev = 0.0;
};

struct HdrMergeSettings {
  CameraTransfer camera_transfer;
  // 8-bit codes at or above `clip_code` are clipped (the light is unknown,
  // only bounded below); at or below `dark_code` they are mostly noise.
  int clip_code = 250;
  int dark_code = 6;
};

struct HdrMergeResult {
  // Reference exposure's camera linear units: 1 is what the reference frame
  // shows as white; a clipped highlight comes out at its true level.
  ImageRGBF linear;
  // Per pixel, 1 where some channel was clipped even in the shortest
  // exposure: its value is only a lower bound.
  std::vector<std::uint8_t> still_clipped;
};

// A reflection map's texels at or above this (largest channel) clipped in
// the camera: settings.clip_code decoded, divided by the ball's reflectance.
double clippedMapLevel(const HdrMergeSettings& settings, double probe_reflectance);

// Why a bracket cannot be merged (frames of other sizes, none given), or
// empty. Checked by mergeBracket too.
std::string bracketProblem(const std::vector<BracketFrame>& frames);

// The merge. Weight of a code c: the hat min(c - dark, clip - c), zero
// outside (dark, clip), times the frame's exposure ratio (a longer
// exposure measures the same radiance with less relative noise); nothing
// from a frame where any channel of the pixel clipped. A channel no frame
// measured takes the shortest exposure's value if the pixel clipped there
// (a lower bound, flagged in still_clipped), else the longest's (dark).
HdrMergeResult mergeBracket(const std::vector<BracketFrame>& frames, const HdrMergeSettings& settings);

// The exposure ratio of `shorter` to `reference` as the pixels measure it:
// the median, over channels well exposed in both, of linear(shorter) /
// linear(reference). Used to check the EV a bracket claims against what its
// frames show. nullopt when fewer than `min_samples` channels qualify.
std::optional<double> measureExposureRatio(const ImageRGB8& reference, const ImageRGB8& shorter,
                                           const HdrMergeSettings& settings, int min_samples = 200);

}  // namespace probelight::ibl
