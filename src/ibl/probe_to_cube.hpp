// CPU reference of stage 2: the ball's image to a world-aligned cube map.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/mirror_ball.hpp"

namespace probelight::ibl {

struct ProbeToCubeParams {
  int face_size = 64;
  double probe_reflectance = 1.0;
  // Newton steps on the ball normal (reflectedDirectionToPixel), the same
  // count the shader unrolls. 1 leaves 0.008 px at a ball 20 cm away and
  // 0.0004 px at 40 cm, 2 leave 4e-8 px (MirrorBall.PixelToDirectionToPixelRoundTrips):
  // 1 is already below what a mediump texture coordinate resolves (~0.3 px
  // at 640 px) and below the ball outline's own error (0.01 px).
  int normal_iterations = 1;
  // At most samples_per_axis^2 directions spread over each texel (1: its
  // centre, as the GPU stage does); a texel takes as many a side as the
  // pixels it spans. Near the ball's rim one texel spans many pixels; a
  // light smaller than a pixel there (the sun in a merged HDR image) is then
  // caught by some sample instead of being hit or missed whole by the
  // centre.
  int samples_per_axis = 1;
  CameraTransfer camera_transfer;  // how the image's values decode to linear light
};

// For every texel centre direction r: find the pixel that shows r in the ball
// (reflectedDirectionToPixel with params.normal_iterations), sample the 8-bit
// image bilinearly in its encoded values, decode the camera transfer (sRGB by
// default) to linear light and divide by probe_reflectance. Texels whose direction is not visible get 0.
// Pixel positions follow OpenCV's calibration convention everywhere in
// probelight: pixel (u, v)'s centre is at integer (u, v) (cx ~ (w - 1) / 2),
// as projectToPixel returns. A GL texture is therefore sampled at
// texcoord = (pixel + 0.5) / size. Edges are clamped.
CubeMapRGB probeImageToCubeMap(const MirrorBallView& view, const ImageRGB8& image, const ProbeToCubeParams& params);

// Same for a linear radiance image (an exposure bracket merged by
// ibl/hdr_bracket): sampled bilinearly in linear values, divided by the
// reflectance, unbounded. camera_transfer is not used.
CubeMapRGB probeRadianceToCubeMap(const MirrorBallView& view, const ImageRGBF& linear, const ProbeToCubeParams& params);

// One frame of an exposure bracket, and the ball as that frame saw it (its
// own pose: a hand-held camera moves between exposures).
struct BracketView {
  const ImageRGB8* image = nullptr;
  double ev = 0.0;  // stops from frames[0]'s exposure
  MirrorBallView view;
};

// An exposure bracket merged direction by direction: each sample direction
// of each texel (samples_per_axis as above, spans measured in frames[0]'s
// view) is found in every frame through that frame's own view, and the
// frames' pixels around it are merged as ibl::mergeBracket merges a pixel
// (hat weight times exposure ratio, each pixel weighted before the
// bilinear sum, so a clipped pixel adds nothing). Registering each frame
// by its own pose, rather than merging pixels at the same place, is what
// lets a camera that moved between exposures be merged. Values are in
// frames[0]'s camera linear units divided by the reflectance.
// still_clipped (optional): per texel (face * n^2 + y * n + x), 1 where
// some channel no frame measured clipped even in the shortest exposure (a
// lower bound).
CubeMapRGB bracketToCubeMap(const std::vector<BracketView>& frames, const HdrMergeSettings& merge,
                            const ProbeToCubeParams& params, std::vector<std::uint8_t>* still_clipped = nullptr);

}  // namespace probelight::ibl
