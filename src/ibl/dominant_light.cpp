#include "ibl/dominant_light.hpp"

namespace probelight::ibl {

namespace {
double luminance(const glm::vec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; }
}  // namespace

DominantLight findDominantLight(const CubeMapRGB& diffuse_map, double min_elevation_sin) {
  DominantLight light;
  double best = -1.0;
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < diffuse_map.face_size; ++y) {
      for (int x = 0; x < diffuse_map.face_size; ++x) {
        const glm::dvec3 direction = cubeTexelCenterDirection(face, x, y, diffuse_map.face_size);
        if (direction.z < min_elevation_sin) continue;
        const double value = luminance(diffuse_map.texel(face, x, y));
        if (value > best) {
          best = value;
          light.direction_w = direction;
        }
      }
    }
  }
  if (best <= 0.0) return light;
  const glm::dvec3 toward = glm::dvec3(diffuse_map.sampleBilinear(light.direction_w));
  const glm::dvec3 away = glm::dvec3(diffuse_map.sampleBilinear(-light.direction_w));
  light.rgb = glm::max(toward - away, glm::dvec3(0.0));
  light.found = luminance(glm::vec3(light.rgb)) > 0.0;
  return light;
}

}  // namespace probelight::ibl
