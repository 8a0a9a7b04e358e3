#version 100
// Ratio-form differential rendering: the camera pixel under the ground
// square, decoded to linear light, times the fraction of the ground's light
// that still reaches it, encoded again. The floor darkens by that fraction
// whatever its colour (ibl::compositeByRatio). With a virtual lamp
// (virtual_lamp.glsl; its ratio 0 without one), the lamp's light is added
// to the fraction: camera (s + ratio), as virtual_lamp.frag gives the
// ground elsewhere; the object's shadow from the lamp and the rig in front
// are that pass's, drawn after this near them.
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
#include "virtual_lamp.glsl"

uniform sampler2D u_camera;
uniform sampler2D u_fraction;
uniform vec2 u_image_size_px;
uniform float u_exposure_gain;  // the frame darkened as a shorter exposure would (1: not)
uniform LAMP_PLACE vec2 u_ground_centre_w;     // the vertex shader's square, at this precision
uniform LAMP_PLACE float u_ground_half_size_m;
varying vec2 v_region_uv;

void main() {
  // The background is drawn 1:1 and upright: window pixel -> texture (t = 0 at the top row).
  vec2 camera_uv = vec2(gl_FragCoord.x / u_image_size_px.x, 1.0 - gl_FragCoord.y / u_image_size_px.y);
  vec3 camera = decodeCamera(texture2D(u_camera, camera_uv).rgb);
  vec3 fraction = texture2D(u_fraction, v_region_uv).rgb;
  LAMP_PLACE vec3 ground = vec3(u_ground_centre_w + u_ground_half_size_m * (2.0 * v_region_uv - 1.0), 0.0);
  gl_FragColor = vec4(encodeCamera(u_exposure_gain * camera * (fraction + lampRatio(ground))), 1.0);
}
