// CPU reference of stage 4: the seeds' shading equation (seed A),
//   c = A_l * A_m + K_d * D_map(n) * albedo + K_s * S_l * max(n.h, 0)^shininess + K_r * R_map(reflect(-v, n)),
// in linear light, with Blinn-Phong's half vector h = normalize(l + v).
#pragma once

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
};

struct SceneLighting {
  glm::vec3 ambient_rgb{0.0f};                    // A_l
  glm::vec3 highlight_direction_w{0.0f, 0.0f, 1.0f};  // unit, toward the light
  glm::vec3 highlight_rgb{0.0f};                  // S_l
};

// normal_w and to_eye_w are unit vectors in W. Maps are sampled bilinearly.
glm::vec3 shadeSurface(const glm::vec3& normal_w, const glm::vec3& to_eye_w, const CubeMapRGB& diffuse_map,
                       const CubeMapRGB& reflection_map, const SurfaceMaterial& material, const SceneLighting& lighting);

}  // namespace probelight::ibl
