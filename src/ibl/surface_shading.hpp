// CPU reference of stage 4: the seeds' shading equation (seed A),
//   c = A_l * A_m + K_d * D_map(n) * albedo + K_s * S_l * max(n.h, 0)^shininess + K_r * R_map(reflect(-v, n)),
// in linear light, with Blinn-Phong's half vector h = normalize(l + v).
//
// Glossiness (seed C: materials blend between the two nearest maps): the
// reflection term K_r * R reads a ladder of maps from sharp to blurred,
//   rung 0             the mirror map at reflect(-v, n),
//   rungs 1..L         the glossy maps (cos^128, cos^16 lobes by default;
//                      src/ibl/glossy_maps.hpp) at reflect(-v, n),
//   rung L + 1         the diffuse map at n (its clamped-cosine lobe about
//                      the normal: E(n) / pi, the same units of mean radiance),
// at position p = (1 - glossiness) (L + 1), linearly between rungs floor(p)
// and floor(p) + 1. Glossiness 1 is exactly today's mirror term (the
// default, so nothing changes for existing materials) and 0 exactly K_r
// times the diffuse map's sample; p is exact at both ends in floats, and
// a rung with weight 0 is not read. The rungs are spaced evenly, and the
// lobe widths step geometrically (sigma 0, 0.088, 0.25, ~0.6 rad), so
// glossiness is roughly linear in log(width).
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

struct SurfaceMaterial {
  glm::vec3 albedo{0.8f, 0.8f, 0.8f};  // D_m
  float ambient = 0.0f;                // A_m
  float k_diffuse = 1.0f;              // K_d
  float k_specular = 0.0f;             // K_s
  float shininess = 32.0f;             // n
  float k_reflect = 0.0f;              // K_r
  float glossiness = 1.0f;             // [0, 1]: 1 mirror, 0 the diffuse lobe; see above
};

// Whether this material reads a glossy map: K_r > 0 and 0 < glossiness < 1.
// The app makes the glossy maps (EnvironmentMaps::updateGlossy) only when
// some object needs them; otherwise the ladder has no glossy rungs to read.
bool needsGlossy(const SurfaceMaterial& material);

// The two rungs and the weight of the upper one for `glossiness` with
// `glossy_levels` glossy maps: R = mix(rung(lower), rung(lower + 1), toward_next).
struct ReflectionLadderBlend {
  int lower = 0;
  float toward_next = 0.0f;
};
ReflectionLadderBlend reflectionLadderBlend(float glossiness, int glossy_levels);

struct SceneLighting {
  glm::vec3 ambient_rgb{0.0f};                    // A_l
  glm::vec3 highlight_direction_w{0.0f, 0.0f, 1.0f};  // unit, toward the light
  glm::vec3 highlight_rgb{0.0f};                  // S_l
  // The light that clipped in the ball's 8-bit image (a sun, a lamp), as
  // found by a bracket or the tag's white border (ibl/white_reference.hpp:
  // clippedLights). Added to the diffuse map's value at n as
  // clipped_diffuse_rgb * max(0, n . clipped_direction_w), in the diffuse
  // map's units (E / pi). Unused entries are 0.
  static constexpr int kMaxClippedLights = 4;
  std::array<glm::vec3, kMaxClippedLights> clipped_direction_w{};
  std::array<glm::vec3, kMaxClippedLights> clipped_diffuse_rgb{};
  // The dome lights' irradiances (a model's self-shadow subtracts them) are
  // kept as fitted; this brings them into the maps' units, as the fields
  // above already are (stages/frame_response.hpp).
  glm::vec3 dome_rgb_scale{1.0f};
  // A virtual lamp (ibl/virtual_lamp.hpp) as the object sees it from its
  // middle: added to the diffuse map's value at n as lamp_diffuse_rgb *
  // max(0, n . lamp_direction_w), in the diffuse map's units (E / pi); 0:
  // no lamp.
  glm::vec3 lamp_direction_w{0.0f, 0.0f, 1.0f};
  glm::vec3 lamp_diffuse_rgb{0.0f};
};

// normal_w and to_eye_w are unit vectors in W. Maps are sampled bilinearly.
glm::vec3 shadeSurface(const glm::vec3& normal_w, const glm::vec3& to_eye_w, const CubeMapRGB& diffuse_map,
                       const CubeMapRGB& reflection_map, const SurfaceMaterial& material, const SceneLighting& lighting);
// The same with glossy maps (sharpest first; none: the ladder is mirror, diffuse).
glm::vec3 shadeSurface(const glm::vec3& normal_w, const glm::vec3& to_eye_w, const CubeMapRGB& diffuse_map,
                       const CubeMapRGB& reflection_map, const std::vector<const CubeMapRGB*>& glossy_maps,
                       const SurfaceMaterial& material, const SceneLighting& lighting);

}  // namespace probelight::ibl
