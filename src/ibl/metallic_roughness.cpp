#include "ibl/metallic_roughness.hpp"
#include "core/math_constants.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <mutex>

namespace probelight::ibl {

namespace {

// The fit's angles from the axis: 1 to 89 degrees.
constexpr int kFitAngles = 89;
// Midpoint steps over the light's 90 degrees: the lobe of alpha 0.046 is
// 3 degrees wide, 40 steps.
constexpr int kLobeSteps = 1200;

double ggxD(double cos_h, double alpha) {
  const double a2 = alpha * alpha;
  const double d = cos_h * cos_h * (a2 - 1.0) + 1.0;
  return a2 / (kPi * d * d);
}

// GGX's lobe at n = v over the light's angle theta_l from the axis: the
// split-sum's sample density D(h) / 4 (h halfway, at theta_l / 2) times its
// weight n.l, per unit theta_l (sin theta_l for the solid angle).
double ggxLobeDensity(double theta_l, double alpha) {
  return ggxD(std::cos(0.5 * theta_l), alpha) / 4.0 * std::cos(theta_l) * std::sin(theta_l);
}

// The lobe's cumulative energy at 1..kFitAngles degrees, in one pass.
std::array<double, kFitAngles> ggxLobeCumulative(double alpha) {
  std::array<double, kFitAngles> cumulative{};
  const double step = 0.5 * kPi / kLobeSteps;
  double sum = 0.0;
  int next = 0;
  for (int i = 0; i < kLobeSteps; ++i) {
    const double theta = (i + 0.5) * step;
    while (next < kFitAngles && (next + 1) * kPi / 180.0 <= i * step) cumulative[next++] = sum;
    sum += ggxLobeDensity(theta, alpha) * step;
  }
  while (next < kFitAngles) cumulative[next++] = sum;
  for (double& c : cumulative) c /= sum;
  return cumulative;
}

double fitError(double alpha, double exponent) {
  const std::array<double, kFitAngles> ggx = ggxLobeCumulative(alpha);
  double error = 0.0;
  for (int k = 0; k < kFitAngles; ++k) {
    const double d = ggx[static_cast<size_t>(k)] - phongLobeEnergyWithin(exponent, (k + 1) * kPi / 180.0);
    error += d * d;
  }
  return error;
}

double fitGgxAlpha(double exponent) {
  // Golden-section search over log alpha in [1e-3, 1] (the error has one
  // minimum there; for the cosine lobe it is at alpha = 1 itself).
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double low = std::log(1e-3), high = 0.0;
  double a = high - golden * (high - low), b = low + golden * (high - low);
  double fa = fitError(std::exp(a), exponent), fb = fitError(std::exp(b), exponent);
  for (int iteration = 0; iteration < 60; ++iteration) {
    if (fa < fb) {
      high = b;
      b = a;
      fb = fa;
      a = high - golden * (high - low);
      fa = fitError(std::exp(a), exponent);
    } else {
      low = a;
      a = b;
      fa = fb;
      b = low + golden * (high - low);
      fb = fitError(std::exp(b), exponent);
    }
  }
  return std::exp(0.5 * (low + high));
}

}  // namespace

glm::vec3 multiBounceVisibility(const glm::vec3& visibility, const glm::vec3& albedo) {
  const glm::vec3 a = 2.0404f * albedo - 0.3324f;
  const glm::vec3 b = -4.7951f * albedo + 0.6417f;
  const glm::vec3 c = 2.7552f * albedo + 0.6903f;
  return glm::max(visibility, ((visibility * a + b) * visibility + c) * visibility);
}

double ggxLobeEnergyWithin(double alpha, double theta_rad) {
  const double step = 0.5 * kPi / kLobeSteps;
  double within = 0.0, total = 0.0;
  for (int i = 0; i < kLobeSteps; ++i) {
    const double theta = (i + 0.5) * step;
    const double e = ggxLobeDensity(theta, alpha) * step;
    total += e;
    if (theta < theta_rad) within += e;
  }
  return within / total;
}

double phongLobeEnergyWithin(double exponent, double theta_rad) {
  // The integral of cos^n sin over [0, theta], over the hemisphere's.
  return 1.0 - std::pow(std::cos(std::clamp(theta_rad, 0.0, 0.5 * kPi)), exponent + 1.0);
}

double ggxAlphaOfPhongExponent(double exponent) {
  static std::mutex mutex;
  static std::map<double, double> fitted;
  std::lock_guard<std::mutex> lock(mutex);
  auto found = fitted.find(exponent);
  if (found == fitted.end()) found = fitted.emplace(exponent, fitGgxAlpha(std::max(exponent, 0.0))).first;
  return found->second;
}

std::vector<double> specularRungAlphas(const std::vector<double>& glossy_exponents) {
  std::vector<double> alphas{0.0};
  for (double exponent : glossy_exponents) alphas.push_back(ggxAlphaOfPhongExponent(exponent));
  // The diffuse map's cosine lobe is GGX's at alpha 1 exactly (D = 1 / pi).
  alphas.push_back(1.0);
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
  diffuse += lighting.lamp_diffuse_rgb * std::max(0.0f, glm::dot(normal_w, lighting.lamp_direction_w));
  glm::vec3 mirror_w = glm::reflect(-to_eye_w, normal_w);
  glm::vec3 floor_fraction(1.0f);
  glm::vec4 camera_floor(0.0f);
  if (near_floor != nullptr) {
    const NearFloorLookup lookup = nearFloorLookup(near_floor->point_w, mirror_w, near_floor->ball);
    mirror_w = lookup.map_direction_w;
    if (lookup.meets_ground && near_floor->fraction) floor_fraction = near_floor->fraction(glm::vec2(lookup.ground_point_w));
    if (lookup.meets_ground && near_floor->camera_floor) camera_floor = near_floor->camera_floor(lookup.ground_point_w);
  }
  const int last = static_cast<int>(rung_alphas.size()) - 1;
  const auto rung = [&](int k) -> glm::vec3 {
    if (k >= last) return diffuse;
    const CubeMapRGB* map = k == 0 ? &reflection_map
                                   : (k - 1 < static_cast<int>(glossy_maps.size()) ? glossy_maps[static_cast<size_t>(k - 1)]
                                                                                  : nullptr);
    if (map == nullptr || map->face_size <= 0) return glm::vec3(0);
    glm::vec3 seen = map->sampleBilinear(glm::dvec3(mirror_w));
    if (k == 0) seen = glm::mix(seen, glm::vec3(camera_floor), camera_floor.a);
    return floor_fraction * seen;
  };
  const ReflectionLadderBlend blend = specularLadderBlend(roughness, rung_alphas);
  glm::vec3 specular = rung(blend.lower);
  if (blend.toward_next > 0.0f) specular = glm::mix(specular, rung(blend.lower + 1), blend.toward_next);
  const float occlusion = std::clamp(surface.occlusion, 0.0f, 1.0f);
  return occlusion * (c_diff * (1.0f - specular_reflectance) * diffuse + specular_reflectance * specular) +
         surface.emissive;
}

}  // namespace probelight::ibl
