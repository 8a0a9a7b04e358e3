#include "ibl/surface_shading.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {

bool needsGlossy(const SurfaceMaterial& material) {
  return material.k_reflect > 0.0f && material.glossiness > 0.0f && material.glossiness < 1.0f;
}

ReflectionLadderBlend reflectionLadderBlend(float glossiness, int glossy_levels) {
  // Single precision, as sphere_object.frag: (1 - 1) * k = 0 and (1 - 0) * k = k exactly.
  const float position = (1.0f - std::clamp(glossiness, 0.0f, 1.0f)) * static_cast<float>(glossy_levels + 1);
  const float lower = std::floor(position);
  return {static_cast<int>(lower), position - lower};
}

glm::vec3 shadeSurface(const glm::vec3& normal_w, const glm::vec3& to_eye_w, const CubeMapRGB& diffuse_map,
                       const CubeMapRGB& reflection_map, const SurfaceMaterial& material, const SceneLighting& lighting) {
  return shadeSurface(normal_w, to_eye_w, diffuse_map, reflection_map, {}, material, lighting);
}

glm::vec3 shadeSurface(const glm::vec3& normal_w, const glm::vec3& to_eye_w, const CubeMapRGB& diffuse_map,
                       const CubeMapRGB& reflection_map, const std::vector<const CubeMapRGB*>& glossy_maps,
                       const SurfaceMaterial& material, const SceneLighting& lighting) {
  // Single precision on purpose: the fragment shader computes this in floats.
  const glm::vec3 half_vector = glm::normalize(lighting.highlight_direction_w + to_eye_w);
  const float highlight = std::pow(std::max(glm::dot(normal_w, half_vector), 0.0f), material.shininess);
  const glm::vec3 mirror_w = glm::reflect(-to_eye_w, normal_w);
  glm::vec3 diffuse = diffuse_map.face_size > 0 ? diffuse_map.sampleBilinear(glm::dvec3(normal_w)) : glm::vec3(0);
  for (int k = 0; k < SceneLighting::kMaxClippedLights; ++k)
    diffuse += lighting.clipped_diffuse_rgb[k] * std::max(0.0f, glm::dot(normal_w, lighting.clipped_direction_w[k]));
  diffuse += lighting.lamp_diffuse_rgb * std::max(0.0f, glm::dot(normal_w, lighting.lamp_direction_w));
  const int levels = static_cast<int>(glossy_maps.size());
  const auto rung = [&](int k) -> glm::vec3 {
    if (k >= levels + 1) return diffuse;
    const CubeMapRGB& map = k == 0 ? reflection_map : *glossy_maps[static_cast<size_t>(k - 1)];
    return map.face_size > 0 ? map.sampleBilinear(glm::dvec3(mirror_w)) : glm::vec3(0);
  };
  const ReflectionLadderBlend blend = reflectionLadderBlend(material.glossiness, levels);
  glm::vec3 reflection = rung(blend.lower);
  if (blend.toward_next > 0.0f) reflection = glm::mix(reflection, rung(blend.lower + 1), blend.toward_next);
  return lighting.ambient_rgb * material.ambient + material.k_diffuse * diffuse * material.albedo +
         material.k_specular * lighting.highlight_rgb * highlight + material.k_reflect * reflection;
}

}  // namespace probelight::ibl
