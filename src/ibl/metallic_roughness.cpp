#include "ibl/metallic_roughness.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {

double ggxAlphaOfPhongExponent(double exponent) { return 1.0 / std::sqrt(2.0 * std::max(exponent, 0.0) + 1.0); }

std::vector<double> specularRungAlphas(const std::vector<double>& glossy_exponents) {
  std::vector<double> alphas{0.0};
  for (double exponent : glossy_exponents) alphas.push_back(ggxAlphaOfPhongExponent(exponent));
  alphas.push_back(ggxAlphaOfPhongExponent(1.0));
  return alphas;
}

ReflectionLadderBlend specularLadderBlend(float roughness, const std::vector<double>& rung_alphas) {
  const float r = std::isnan(roughness) ? 1.0f : std::clamp(roughness, 0.0f, 1.0f);
  const double alpha = static_cast<double>(r) * r;
  const int last = static_cast<int>(rung_alphas.size()) - 1;
  if (last <= 0) return {0, 0.0f};
  for (int k = 0; k < last; ++k) {
    const double low = rung_alphas[static_cast<size_t>(k)], high = rung_alphas[static_cast<size_t>(k + 1)];
    if (alpha < high) return {k, static_cast<float>((alpha - low) / (high - low))};
  }
  return {last, 0.0f};
}

RungRange specularRungRange(float min_roughness, float max_roughness, const std::vector<double>& rung_alphas) {
  const ReflectionLadderBlend low = specularLadderBlend(min_roughness, rung_alphas);
  const ReflectionLadderBlend high = specularLadderBlend(max_roughness, rung_alphas);
  RungRange range{low.lower, high.toward_next > 0.0f ? high.lower + 1 : high.lower};
  range.last = std::max(range.last, range.first);
  return range;
}

glm::vec3 shadeMetallicRoughness(const glm::vec3& normal_w, const glm::vec3& to_eye_w,
                                 const MetallicRoughnessSurface& surface, const CubeMapRGB& diffuse_map,
                                 const CubeMapRGB& reflection_map, const std::vector<const CubeMapRGB*>& glossy_maps,
                                 const std::vector<double>& rung_alphas, const EnvironmentBrdfTable& brdf_table,
                                 const SceneLighting& lighting, const NearFloorShading* near_floor) {
  const float metallic = std::clamp(surface.metallic, 0.0f, 1.0f);
  const float roughness = std::clamp(surface.roughness, 0.0f, 1.0f);
  const glm::vec3 base = glm::clamp(surface.base_color, 0.0f, 1.0f);
  const glm::vec3 c_diff = base * (1.0f - metallic);
  const glm::vec3 f0 = glm::mix(glm::vec3(0.04f), base, metallic);
  // n.v of a normal turned away from the eye (interpolated normals, normal
  // maps) is taken as the grazing limit rather than a negative cosine.
  const float n_dot_v = std::max(glm::dot(normal_w, to_eye_w), 1e-4f);
  const EnvironmentBrdf brdf = brdf_table.lookup(roughness, n_dot_v);
  const glm::vec3 specular_reflectance = f0 * static_cast<float>(brdf.scale) + static_cast<float>(brdf.bias);

  glm::vec3 diffuse = diffuse_map.face_size > 0 ? diffuse_map.sampleBilinear(glm::dvec3(normal_w)) : glm::vec3(0);
  for (int k = 0; k < SceneLighting::kMaxClippedLights; ++k)
    diffuse += lighting.clipped_diffuse_rgb[k] * std::max(0.0f, glm::dot(normal_w, lighting.clipped_direction_w[k]));
  glm::vec3 mirror_w = glm::reflect(-to_eye_w, normal_w);
  glm::vec3 floor_fraction(1.0f);
  if (near_floor != nullptr) {
    const NearFloorLookup lookup = nearFloorLookup(near_floor->point_w, mirror_w, near_floor->ball);
    mirror_w = lookup.map_direction_w;
    if (lookup.meets_ground && near_floor->fraction) floor_fraction = near_floor->fraction(glm::vec2(lookup.ground_point_w));
  }
  const int last = static_cast<int>(rung_alphas.size()) - 1;
  const auto rung = [&](int k) -> glm::vec3 {
    if (k >= last) return diffuse;
    const CubeMapRGB* map = k == 0 ? &reflection_map
                                   : (k - 1 < static_cast<int>(glossy_maps.size()) ? glossy_maps[static_cast<size_t>(k - 1)]
                                                                                  : nullptr);
    return map != nullptr && map->face_size > 0 ? floor_fraction * map->sampleBilinear(glm::dvec3(mirror_w))
                                                : glm::vec3(0);
  };
  const ReflectionLadderBlend blend = specularLadderBlend(roughness, rung_alphas);
  glm::vec3 specular = rung(blend.lower);
  if (blend.toward_next > 0.0f) specular = glm::mix(specular, rung(blend.lower + 1), blend.toward_next);
  const float occlusion = std::clamp(surface.occlusion, 0.0f, 1.0f);
  return occlusion * (c_diff * (1.0f - specular_reflectance) * diffuse + specular_reflectance * specular) +
         surface.emissive;
}

}  // namespace probelight::ibl
