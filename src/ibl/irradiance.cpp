#include "ibl/irradiance.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {

glm::dvec3 irradianceFromCubeMap(const CubeMapRGB& cube, const glm::dvec3& normal) {
  // A NaN or zero normal has no hemisphere: 0, not NaN.
  if (!std::isfinite(normal.x) || !std::isfinite(normal.y) || !std::isfinite(normal.z) ||
      (normal.x == 0.0 && normal.y == 0.0 && normal.z == 0.0))
    return glm::dvec3(0.0);
  const glm::dvec3 n = glm::normalize(normal);
  const int size = cube.face_size;
  glm::dvec3 sum(0.0);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const double cosine = glm::dot(n, cubeTexelCenterDirection(face, x, y, size));
        if (cosine <= 0.0) continue;
        const glm::vec3& texel = cube.texel(face, x, y);
        // A non-finite texel is unknown, as in projectToSH9: it adds nothing.
        if (!std::isfinite(texel.r) || !std::isfinite(texel.g) || !std::isfinite(texel.b)) continue;
        sum += glm::dvec3(cube.texel(face, x, y)) * (cosine * cubeTexelSolidAngle(x, y, size));
      }
    }
  }
  return sum;
}

}  // namespace probelight::ibl
