// A first, crude dominant light for the highlight term of the shading
// equation: where the diffuse map is brightest in the upper hemisphere, and
// how much brighter that side is than the opposite one. The dome of
// shadow-casting lights replaces this in a later issue.
#pragma once

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

struct DominantLight {
  bool found = false;
  glm::dvec3 direction_w{0.0, 0.0, 1.0};  // unit, toward the light
  glm::dvec3 rgb{0.0};                    // directional excess, linear camera units
};

// Scans texel centres with direction z >= min_elevation_sin. The colour is
// D(d) - D(-d), clamped at 0: a uniform environment has no dominant light.
DominantLight findDominantLight(const CubeMapRGB& diffuse_map, double min_elevation_sin = 0.05);

}  // namespace probelight::ibl
