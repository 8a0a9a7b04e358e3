// Brute-force irradiance from a cube map: the ground truth that the cheap
// blurred diffuse map is calibrated against, and that tests compare with.
#pragma once

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

// E(n) = sum over all texels of L * max(0, n . omega) * solid angle, omega the
// texel's centre direction; `normal` need not be unit length. For a constant
// map of radiance L this is pi * L (up to the texel-centre quadrature error).
// Cost is 6 * face_size^2 per call.
glm::dvec3 irradianceFromCubeMap(const CubeMapRGB& cube, const glm::dvec3& normal);

}  // namespace probelight::ibl
