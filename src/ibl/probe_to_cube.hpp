// CPU reference of stage 2: the ball's image to a world-aligned cube map.
#pragma once

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"

namespace probelight::ibl {

struct ProbeToCubeParams {
  int face_size = 64;
  double probe_reflectance = 1.0;
  int normal_iterations = 4;  // fixed-point steps, the same count the shader unrolls
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

}  // namespace probelight::ibl
