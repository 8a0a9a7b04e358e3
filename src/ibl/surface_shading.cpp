#include "ibl/surface_shading.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {

glm::vec3 shadeSurface(const glm::vec3& normal_w, const glm::vec3& to_eye_w, const CubeMapRGB& diffuse_map,
                       const CubeMapRGB& reflection_map, const SurfaceMaterial& material, const SceneLighting& lighting) {
  // Single precision on purpose: the fragment shader computes this in floats.
  const glm::vec3 half_vector = glm::normalize(lighting.highlight_direction_w + to_eye_w);
  const float highlight = std::pow(std::max(glm::dot(normal_w, half_vector), 0.0f), material.shininess);
  const glm::vec3 mirror_w = glm::reflect(-to_eye_w, normal_w);
  const glm::vec3 diffuse = diffuse_map.face_size > 0 ? diffuse_map.sampleBilinear(glm::dvec3(normal_w)) : glm::vec3(0);
  const glm::vec3 reflection =
      reflection_map.face_size > 0 ? reflection_map.sampleBilinear(glm::dvec3(mirror_w)) : glm::vec3(0);
  return lighting.ambient_rgb * material.ambient + material.k_diffuse * diffuse * material.albedo +
         material.k_specular * lighting.highlight_rgb * highlight + material.k_reflect * reflection;
}

}  // namespace probelight::ibl
