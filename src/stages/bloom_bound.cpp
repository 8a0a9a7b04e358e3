#include "stages/bloom_bound.hpp"

#include <algorithm>

#include "model/mesh_model.hpp"

namespace probelight {

double objectLightBound(const SceneObject& object, const ibl::SceneLighting& lighting, double reflection_peak,
                        const glm::dvec3& response_gain) {
  const double reflection = std::max(reflection_peak, 0.0);
  // The clipped lights add to the diffuse term at most their whole
  // irradiance (n . l <= 1).
  glm::dvec3 clipped(0.0);
  for (const glm::vec3& rgb : lighting.clipped_diffuse_rgb) clipped += glm::max(glm::dvec3(rgb), glm::dvec3(0.0));
  clipped += glm::max(glm::dvec3(lighting.lamp_diffuse_rgb), glm::dvec3(0.0));  // a virtual lamp, as one more
  const glm::dvec3 gain = glm::max(response_gain, glm::dvec3(0.0));
  glm::dvec3 gained(0.0);
  if (object.isModel()) {
    // model_object.frag: occlusion [c_diff (1 - E_s) D + E_s R] + emissive,
    // with c_diff and occlusion at most 1 and the split-sum's E_s = F0
    // scale + bias in [0, 1]: a mix of D and R, so at most the larger.
    // D is the diffuse map (a mean of the reflection map) with the clipped
    // lights; R the reflection, or the floor seen beside the model, white
    // at most in the frame's own units. Plus the brightest emissive (its
    // texture at most 1).
    glm::dvec3 emissive(0.0);
    for (const model::Material& material : object.model->materials)
      emissive = glm::max(emissive, glm::dvec3(material.emissive_factor));
    gained = gain * emissive + glm::max(gain * (glm::dvec3(reflection) + clipped), glm::dvec3(1.0));
  } else {
    // sphere_object.frag: ambient A + k_d albedo (diffuse + clipped) +
    // k_s S (Blinn-Phong at most 1) + k_r reflection.
    const ibl::SurfaceMaterial& m = object.material;
    const glm::dvec3 light =
        glm::dvec3(lighting.ambient_rgb) * static_cast<double>(m.ambient) +
        static_cast<double>(m.k_diffuse) * glm::dvec3(m.albedo) * (glm::dvec3(reflection) + clipped) +
        static_cast<double>(m.k_specular) * glm::max(glm::dvec3(lighting.highlight_rgb), glm::dvec3(0.0)) +
        static_cast<double>(m.k_reflect) * reflection;
    gained = gain * light;
  }
  return std::max({gained.r, gained.g, gained.b});
}

}  // namespace probelight
