#include "ibl/irradiance.hpp"

#include <algorithm>

namespace probelight::ibl {

glm::dvec3 irradianceFromCubeMap(const CubeMapRGB& cube, const glm::dvec3& normal) {
  const glm::dvec3 n = glm::normalize(normal);
  const int size = cube.face_size;
  glm::dvec3 sum(0.0);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < size; ++y) {
      for (int x = 0; x < size; ++x) {
        const double cosine = glm::dot(n, cubeTexelCenterDirection(face, x, y, size));
        if (cosine <= 0.0) continue;
        sum += glm::dvec3(cube.texel(face, x, y)) * (cosine * cubeTexelSolidAngle(x, y, size));
      }
    }
  }
  return sum;
}

}  // namespace probelight::ibl
