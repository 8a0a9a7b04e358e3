// When the bloom has nothing to spread (issue 19: "skipped when nothing
// exceeds white"): an upper bound of the object's light, in units of
// white, per the shading equations, from what the CPU knows without a
// read-back: the reflection map's brightest texel, the clipped lights, the
// highlight, the materials' emissive, and the camera's response gain. The
// object's light is at most this; at or below 1 nothing of it is clipped,
// so the bloom would add nothing. Pure.
#pragma once

#include <glm/glm.hpp>

#include "ibl/surface_shading.hpp"
#include "stages/scene_object.hpp"

namespace probelight {

// reflection_peak: the reflection map's largest channel value (its
// glossy and diffuse maps are weighted means of it, so never more).
// response_gain: camera_response.glsl's u_response_gain_rgb.
double objectLightBound(const SceneObject& object, const ibl::SceneLighting& lighting, double reflection_peak,
                        const glm::dvec3& response_gain);

}  // namespace probelight
