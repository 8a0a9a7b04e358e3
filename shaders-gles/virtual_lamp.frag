#version 100
// The virtual lamp's light on the real ground (passes/virtual_lamp_light,
// ibl/virtual_lamp.hpp): over the whole frame (virtual_lamp.vert gives each
// pixel its camera ray in W, and the ground point is where it meets z = 0),
// the camera pixel decoded to linear light times the exposure gain and
// (s + ratio), encoded again (in the whole-frame draw without decoding
// it). s is the dome's shadow fraction where its square reaches (1
// elsewhere), ratio the lamp's irradiance over the
// room's (0 above the horizon):
// ratio_1m cos(theta) / d^2, the spot's smoothstep of the cosine off its
// axis, and the object's shadow from the lamp (u_lamp_shadow over its own
// square about the shadow, 0 where the lamp is hidden). The albedo is the pixel over the room's irradiance, so
// the pixel times the ratio is the lamp's light off it.
//
// Pixels where the camera sees the rig's ball or post in front of the
// ground are not the ground: they get s alone, as the shadow's pass gives
// them.
//
// Precision: d^2 and d^3 of a lamp 2 cm to 1 m away lie in 4e-4 .. 1; at
// 16-bit mediump their relative steps are 2^-10, a tenth of an 8-bit step
// of the ratio; the ball's ray test wants highp (the ray's square terms),
// and is left to mediump's 2^-10 m only where highp is missing.
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
#include "virtual_lamp.glsl"

#ifdef PL_FRAGMENT_HIGHP
#define PLACE highp
#else
#define PLACE mediump
#endif

uniform sampler2D u_camera;
uniform sampler2D u_lamp_shadow;
uniform sampler2D u_dome_shadow;
uniform vec2 u_image_size_px;
uniform PLACE vec2 u_mask_centre_w;     // the square u_lamp_shadow covers
uniform PLACE float u_mask_half_size_m;  // 0: no shadow from the lamp
uniform PLACE vec2 u_dome_centre_w;
uniform PLACE float u_dome_half_size_m;  // 0: no dome shadow
uniform PLACE vec3 u_eye_w;
uniform PLACE vec4 u_ball_w;      // centre, radius
uniform PLACE vec3 u_post_w;      // x, y, radius (up to the ball's bottom)
uniform float u_exposure_gain;    // the frame darkened as a shorter exposure would (1: not)
uniform vec4 u_rig_rect_px;         // the ball's and post's window rectangle: x0, y0, x1, y1
varying PLACE vec3 v_ray_w;

// Within the square of half size `half_size` about `centre`, the point's
// place in it as uv; outside, a uv past [0, 1].
PLACE vec2 squareUv(PLACE vec2 point, PLACE vec2 centre, PLACE float half_size) {
  return (point - centre) / (2.0 * half_size) + 0.5;
}
bool inUnitSquare(PLACE vec2 uv) { return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0))); }

// Whether the segment from the eye to the ground point meets the ball or
// the post before it.
bool rigInFront(PLACE vec3 ground) {
  PLACE vec3 ray = ground - u_eye_w;
  PLACE vec3 from_centre = u_eye_w - u_ball_w.xyz;
  PLACE float a = dot(ray, ray);
  PLACE float b = dot(from_centre, ray);
  PLACE float c = dot(from_centre, from_centre) - u_ball_w.w * u_ball_w.w;
  PLACE float disc = b * b - a * c;
  if (disc > 0.0) {
    PLACE float t = (-b - sqrt(disc)) / a;
    if (t > 0.0 && t < 1.0) return true;
  }
  if (u_post_w.z > 0.0) {
    PLACE vec2 ray2 = ray.xy;
    PLACE vec2 from_axis = u_eye_w.xy - u_post_w.xy;
    PLACE float a2 = dot(ray2, ray2);
    PLACE float b2 = dot(from_axis, ray2);
    PLACE float c2 = dot(from_axis, from_axis) - u_post_w.z * u_post_w.z;
    PLACE float disc2 = b2 * b2 - a2 * c2;
    if (a2 > 0.0 && disc2 > 0.0) {
      PLACE float t2 = (-b2 - sqrt(disc2)) / a2;
      PLACE float z = u_eye_w.z + t2 * ray.z;
      if (t2 > 0.0 && t2 < 1.0 && z < u_ball_w.z - u_ball_w.w) return true;
    }
  }
  return false;
}

void main() {
  vec2 camera_uv = vec2(gl_FragCoord.x / u_image_size_px.x, 1.0 - gl_FragCoord.y / u_image_size_px.y);
  vec3 encoded = texture2D(u_camera, camera_uv).rgb;
  PLACE vec3 ground = u_eye_w + (-u_eye_w.z / min(v_ray_w.z, -1e-6)) * v_ray_w;
  ground.z = 0.0;
  // Above the horizon: no ground, no lamp.
  vec3 ratio = v_ray_w.z < 0.0 ? lampRatio(ground) : vec3(0.0);
#ifndef LAMP_DETAIL
  // Over the frame: the camera's values scaled by gain x (s + ratio)
  // (camera_transfer.glsl). s is read everywhere and chosen by a step, not
  // a branch: llvmpipe would pay for both sides. The fraction texture is
  // exactly 1 (255) wherever the dome's shadow darkens by under half a
  // step, so this is the shadow's own composite, folded in. (Drawing it
  // apart where the shadow's cells are, marked in the depth buffer, cost
  // more on llvmpipe: its depth test does not spare the shader's work.)
  PLACE vec2 dome_uv = squareUv(ground.xy, u_dome_centre_w, max(u_dome_half_size_m, 1e-3));
  PLACE vec2 dome_inside = step(vec2(0.0), dome_uv) * step(dome_uv, vec2(1.0));
  float in_dome = dome_inside.x * dome_inside.y * step(1e-6, u_dome_half_size_m) * step(v_ray_w.z, 0.0);
  vec3 light = mix(vec3(1.0), texture2D(u_dome_shadow, dome_uv).rgb, in_dome);
  vec3 scale = u_exposure_gain * (light + ratio);
  gl_FragColor = vec4(scaleEncodedCamera(encoded, scale), 1.0);
#else
  // Near the object and the rig (this variant's draw is cut to their
  // rectangle of the frame: a GPU without real branches, llvmpipe, would
  // pay for these reads and tests at every pixel): the dome's shadow, the
  // object's shadow from the lamp, and the rig in front of the ground.
  vec3 light = vec3(1.0);
  if (v_ray_w.z < 0.0) {
    if (u_dome_half_size_m > 0.0) {
      PLACE vec2 dome_uv = squareUv(ground.xy, u_dome_centre_w, u_dome_half_size_m);
      if (inUnitSquare(dome_uv)) light = texture2D(u_dome_shadow, dome_uv).rgb;
    }
    if (u_mask_half_size_m > 0.0) {
      PLACE vec2 mask_uv = squareUv(ground.xy, u_mask_centre_w, u_mask_half_size_m);
      if (inUnitSquare(mask_uv)) ratio *= texture2D(u_lamp_shadow, mask_uv).r;
    }
    bool near_rig = all(greaterThanEqual(gl_FragCoord.xy, u_rig_rect_px.xy)) &&
                    all(lessThanEqual(gl_FragCoord.xy, u_rig_rect_px.zw));
    if (near_rig && rigInFront(ground)) ratio = vec3(0.0);
  }
  gl_FragColor = vec4(encodeCamera(u_exposure_gain * decodeCamera(encoded) * (light + ratio)), 1.0);
#endif
}
