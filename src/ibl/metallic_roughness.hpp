// CPU reference of how the kiosk lights a glTF metallic-roughness surface
// from its maps (the model renderer's shader, shaders-gles/model_object.frag,
// computes the same in GLSL ES 1.00).
//
//   c = occlusion * [ c_diff (1 - E_s) D(n) + E_s R(r, roughness) ] + emissive
//
// with c_diff = base (1 - metallic) and F0 = mix(0.04, base, metallic) as
// glTF 2.0's Appendix B defines them, D the diffuse map at the shading
// normal (mean radiance E / pi, plus the clipped lights' diffuse share, as
// ibl::shadeSurface adds them), r = reflect(-v, n), and E_s the split-sum
// specular reflectance F0 * scale + bias (ibl/environment_brdf.hpp) at
// (roughness, n.v). The diffuse keeps the 1 - E_s the specular did not
// take: glTF's fresnel_mix weighs its diffuse by 1 - F.
//
// R is the specular light: the mirror and glossy maps and the diffuse map
// form a ladder of lobes (ibl/surface_shading.hpp), and a roughness picks a
// place on it. Each rung stands for the GGX lobe (alpha = roughness^2) it
// matches best: the split-sum prefilters GGX with n = v = r (Karis 2013),
// where the lobe over light directions is D(h) / 4 times n.l, and a rung's
// lobe is its map's own (cos^n about r for a glossy map, the clamped cosine
// about n for the diffuse map). The rung's alpha is the one whose lobe puts
// its energy at the same angles: the least-squares fit of the two lobes'
// cumulative energy against the angle from the axis (1 to 89 degrees).
// That gives 0.046 for cos^128 and 0.146 for cos^16, and exactly 1 for the
// diffuse map (GGX at alpha 1 is D = 1 / pi, whose lobe is the cosine).
// Walter et al. 2007's Beckmann-Phong peak equivalence (alpha =
// 1 / sqrt(2 n + 1): 0.062, 0.174, 0.577) matches the peaks' curvature
// alone; GGX's long tail then puts a quarter less of a rough metal's light
// beside its highlights than the path-traced truth shows. A roughness reads
// the two rungs whose alphas bracket its own, linearly in alpha.
//
// The near floor (ibl/near_floor.hpp): where the specular rungs' direction
// r goes down, they are read where the ball sees the ground point r meets
// (the mirror rung from the camera's frame where it shows the point),
// times the ground shadow's fraction there. The diffuse rung (about the
// normal) is left as it is.
//
// Occlusion (the file's baked ambient occlusion) scales all of the light:
// every bit of it is image-based, none is a punctual light it would spare.
#pragma once

#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"
#include "ibl/environment_brdf.hpp"
#include "ibl/near_floor.hpp"
#include "ibl/surface_shading.hpp"

namespace probelight::ibl {

// glTF's material at one point, after textures: base colour linear (the
// sRGB texture decoded, times the factor and the vertex colour).
struct MetallicRoughnessSurface {
  glm::vec3 base_color{1.0f};
  float metallic = 1.0f;
  float roughness = 1.0f;
  float occlusion = 1.0f;  // 1 = unoccluded
  glm::vec3 emissive{0.0f};
};

// The share of a lobe's energy within theta_rad of its axis: GGX's lobe as
// the split-sum prefilters it (n = v = r), and a map's cos^n lobe.
double ggxLobeEnergyWithin(double alpha, double theta_rad);
double phongLobeEnergyWithin(double exponent, double theta_rad);

// The GGX alpha whose lobe a map's cos^n lobe matches best (the
// least-squares fit above); exponent 1 is the diffuse map's cosine lobe
// (alpha 1). Computed once per exponent, then remembered.
double ggxAlphaOfPhongExponent(double exponent);

// The ladder's rung alphas for these glossy map exponents (sharpest first):
// mirror 0, one per glossy map, diffuse 1 / sqrt(3); increasing.
std::vector<double> specularRungAlphas(const std::vector<double>& glossy_exponents);

// Where a roughness sits on the ladder: R = mix(rung(lower), rung(lower + 1),
// toward_next), rungs numbered as in specularRungAlphas (the last is the
// diffuse map). Roughness is clamped to [0, 1]; NaN reads as 1 (glTF's default).
ReflectionLadderBlend specularLadderBlend(float roughness, const std::vector<double>& rung_alphas);

// The rungs a material can read over a range of roughness: [first, last].
struct RungRange {
  int first = 0;
  int last = 0;
};
RungRange specularRungRange(float min_roughness, float max_roughness, const std::vector<double>& rung_alphas);

// The near floor for one surface point: the point, the ball's centre, the
// ground shadow's fraction at a ground point (1 where there is none), and
// the floor as the camera's frame shows it there: linear RGB and its
// weight (cameraFloorWeight; 0 where the frame does not show it).
struct NearFloorShading {
  glm::vec3 point_w{0.0f};
  NearFloorBall ball;
  std::function<glm::vec3(const glm::vec2& ground_point_w)> fraction;
  std::function<glm::vec4(const glm::vec3& ground_point_w)> camera_floor;
};

// A point's self-shadow visibility (the share of its light its own model
// leaves it) lifted by the light the model bounces onto it from where it
// hides the room: Jimenez, Wu, Pesce and Jarabo's multi-bounce fit
// ("Practical real-time strategies for accurate indirect occlusion", 2016),
// V' = max(V, ((a V + b) V + c) V) with a, b, c linear in the albedo, made
// from path-traced ambient occlusion over many scenes. The albedo is the
// surface's own reflectance, standing for its surroundings' on the model.
// Per channel; V and albedo in [0, 1]; V' is V at albedo 0 and 1 at V = 1.
glm::vec3 multiBounceVisibility(const glm::vec3& visibility, const glm::vec3& albedo);

// The lit colour in linear light. normal_w and to_eye_w unit. glossy_maps:
// sharpest first, their exponents the ones rung_alphas were made from.
glm::vec3 shadeMetallicRoughness(const glm::vec3& normal_w, const glm::vec3& to_eye_w,
                                 const MetallicRoughnessSurface& surface, const CubeMapRGB& diffuse_map,
                                 const CubeMapRGB& reflection_map, const std::vector<const CubeMapRGB*>& glossy_maps,
                                 const std::vector<double>& rung_alphas, const EnvironmentBrdfTable& brdf_table,
                                 const SceneLighting& lighting, const NearFloorShading* near_floor = nullptr);

}  // namespace probelight::ibl
