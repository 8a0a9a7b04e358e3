#version 100
// One light's hidden share of the ground's irradiance, share * hidden, which
// GroundShadow subtracts (by blending) from a ground texture cleared to 1:
// after every light, 1 - sum_i share_i * hidden_i, ibl::groundLightFraction's
// model. Each light is drawn only over the ground its shadow can reach
// (shadowFootprintNdc). The light is a cone of half-angle atan(u_tan_cone);
// its hidden share is found PCSS-style: the mean depth of the blockers
// around the point (searched over the widest penumbra the object can cast
// there) gives the occluder's distance t, and the share of shadow-map taps
// within t tan(cone) that are blocked is the share of the cone the object
// hides. The map holds the object's far side from the light
// (ground_shadow.cpp says why).
//
// Precision: the ground point arrives in the light's clip space (made at
// highp in the vertex shader) and depths are in [0, 1] of a few
// centimetres' range; mediump (11 significant bits) resolves depth to
// ~1/2000 of the object's size, which the bias covers.
#include "depth_packing.glsl"

#define TAPS 16
// Below any depth the object can have (its frustum has a 4% margin).
const float kEmpty01 = 0.01;

uniform sampler2D u_shadow_map;
uniform vec3 u_share;
uniform float u_tan_cone;
// How the ground's own depth changes across the map, per unit of uv: the
// receiver is the ground plane, so each tap compares the stored depth with
// the ground's depth at that tap, not at the centre (receiver-plane bias).
uniform vec2 u_ground_gradient;
uniform float u_map_width_m;    // the orthographic frustum's width
uniform float u_depth_range_m;  // and its depth
uniform float u_texel_uv;       // one shadow-map texel, in uv
// A ground point at the object's far side, within this much depth, counts
// as behind it: where the object stands on the ground (a box's bottom face,
// a sphere's contact) the ground is hidden, not lit.
uniform float u_bias01;
uniform vec2 u_taps[TAPS];      // a unit disc, evenly covered
varying vec3 v_light_clip;  // ground_shadow.vert: the ground point in the light's clip space

float storedDepth(vec2 uv) {
#ifdef SHADOW_DEPTH_PACKED
  return unpackDepth(texture2D(u_shadow_map, uv));
#else
  return texture2D(u_shadow_map, uv).r;
#endif
}

void main() {
  vec3 clip = v_light_clip;
  vec2 uv = 0.5 * clip.xy + 0.5;
  // The object lies within depths 0.02-0.98 of its frustum; the map holds
  // its far side and is cleared to 0 where it is absent.
  float receiver = 0.5 * clip.z + 0.5;
  // Blocker search over the penumbra an occluder at the near plane would cast.
  float metres_to_uv = u_tan_cone / u_map_width_m;
  float search_uv = receiver * u_depth_range_m * metres_to_uv + u_texel_uv;
  // NEAREST reads the depth at a texel's centre, up to half a texel
  // diagonal from the tap: that much of the ground's slope, plus the bias.
  float bias = u_bias01 + 0.71 * u_texel_uv * length(u_ground_gradient);
  float blocker_sum = 0.0;
  float blockers = 0.0;
  for (int k = 0; k < TAPS; ++k) {
    vec2 offset = search_uv * u_taps[k];
    float d = storedDepth(uv + offset);
    if (d > kEmpty01 && d < receiver + dot(u_ground_gradient, offset) + bias) {
      blocker_sum += d;
      blockers += 1.0;
    }
  }
  float hidden = 0.0;
  if (blockers > 0.5) {
    float distance_m = (receiver - blocker_sum / blockers) * u_depth_range_m;
    float filter_uv = max(distance_m, 0.0) * metres_to_uv + u_texel_uv;
    for (int k = 0; k < TAPS; ++k) {
      vec2 offset = filter_uv * u_taps[k];
      float d = storedDepth(uv + offset);
      hidden += d > kEmpty01 && d < receiver + dot(u_ground_gradient, offset) + bias ? 1.0 : 0.0;
    }
  }
  // Alpha 0: the texture's alpha stays 1 under the subtraction.
  gl_FragColor = vec4(u_share * (hidden / float(TAPS)), 0.0);
}
