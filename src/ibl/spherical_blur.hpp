// CPU reference of stage 3: a separable Gaussian blur on the sphere of
// directions. Each pass samples along great circles, so there are no seams at
// cube face edges; two passes along orthogonal tangents give the 2-D blur.
#pragma once

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

enum class BlurAxis {
  kEast = 0,   // tangent t = normalize(cross(world +Z, n)); at the poles (|cross| < 1e-4) t = +X
  kNorth = 1,  // tangent t = cross(n, east tangent)
};

struct SphericalBlurPass {
  BlurAxis axis = BlurAxis::kEast;
  double sigma_rad = 0.6;
  int half_taps = 8;  // samples at i * step for i in [-half_taps, half_taps], step = 3 * sigma / half_taps
};

glm::dvec3 blurTangent(const glm::dvec3& n, BlurAxis axis);

// Output texel (x, y) of face f, with centre direction n, is
//   sum_i w_i * input.sampleBilinear(cos(a_i) n + sin(a_i) t) / sum_i w_i,
//   a_i = i * step, w_i = exp(-a_i^2 / (2 sigma^2)).
CubeMapRGB sphericalBlurPass(const CubeMapRGB& input, int output_face_size, const SphericalBlurPass& pass);

}  // namespace probelight::ibl
