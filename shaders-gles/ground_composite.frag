#version 100
// Ratio-form differential rendering: the camera pixel under the ground
// square, decoded to linear light, times the fraction of the ground's light
// that still reaches it, encoded again. The floor darkens by that fraction
// whatever its colour (ibl::compositeByRatio). (With a virtual lamp, the
// lamp's whole-frame pass, virtual_lamp.frag, gives the ground this
// fraction instead, with the lamp's light added.)
#include "color_transfer.glsl"
#include "camera_transfer.glsl"

uniform sampler2D u_camera;
uniform sampler2D u_fraction;
uniform vec2 u_image_size_px;
uniform float u_exposure_gain;  // the frame darkened as a shorter exposure would (1: not)
varying vec2 v_region_uv;

void main() {
  // The background is drawn 1:1 and upright: window pixel -> texture (t = 0 at the top row).
  vec2 camera_uv = vec2(gl_FragCoord.x / u_image_size_px.x, 1.0 - gl_FragCoord.y / u_image_size_px.y);
  vec3 camera = decodeCamera(texture2D(u_camera, camera_uv).rgb);
  vec3 fraction = texture2D(u_fraction, v_region_uv).rgb;
  gl_FragColor = vec4(encodeCamera(u_exposure_gain * camera * fraction), 1.0);
}
