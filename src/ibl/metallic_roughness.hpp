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
// place on it. A GGX lobe of alpha = roughness^2 reflects, near its peak,
// like a Phong lobe cos^n about r with n = 1 / (2 alpha^2) - 1/2 (Walter et
// al. 2007's Beckmann-Phong equivalence, n_h = 2 / alpha^2 - 2, with the
// reflected lobe a quarter of the half-vector exponent). So each rung has an
// alpha: 0 for the mirror, 1 / sqrt(2 n + 1) for a glossy map of exponent n
// (0.062 for n = 128, 0.174 for n = 16), and 1 / sqrt(3) = 0.577 for the
// diffuse map (its clamped cosine is n = 1, about the normal rather than r:
// at that width the two differ by a small share of the lobe). A roughness
// reads the two rungs whose alphas bracket its own, linearly in alpha;
// rougher than the diffuse rung reads the diffuse map alone.
//
// The near floor (ibl/near_floor.hpp): where the specular rungs' direction
// r goes down, they are read where the ball sees the ground point r meets,
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

// The alpha of a Phong lobe cos^n about the reflection direction: 1 / sqrt(2 n + 1).
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

// The near floor for one surface point: the point, the ball's centre, and
// the ground shadow's fraction at a ground point (1 where there is none).
struct NearFloorShading {
  glm::vec3 point_w{0.0f};
  NearFloorBall ball;
  std::function<glm::vec3(const glm::vec2& ground_point_w)> fraction;
};

// The lit colour in linear light. normal_w and to_eye_w unit. glossy_maps:
// sharpest first, their exponents the ones rung_alphas were made from.
glm::vec3 shadeMetallicRoughness(const glm::vec3& normal_w, const glm::vec3& to_eye_w,
                                 const MetallicRoughnessSurface& surface, const CubeMapRGB& diffuse_map,
                                 const CubeMapRGB& reflection_map, const std::vector<const CubeMapRGB*>& glossy_maps,
                                 const std::vector<double>& rung_alphas, const EnvironmentBrdfTable& brdf_table,
                                 const SceneLighting& lighting, const NearFloorShading* near_floor = nullptr);

}  // namespace probelight::ibl
