#version 100
// Stage 3: one pass of the separable Gaussian blur on the sphere of
// directions, the maths of ibl::sphericalBlurPass. Taps run along great
// circles, so nothing depends on cube face edges.
#include "color_transfer.glsl"
#include "cube_storage.glsl"

#ifndef HALF_TAPS
#define HALF_TAPS 8
#endif

varying vec2 v_face_st;

uniform vec3 u_face_center;
uniform vec3 u_face_s_axis;
uniform vec3 u_face_t_axis;
uniform samplerCube u_input;
uniform float u_input_face_size;
uniform float u_input_scale;
uniform float u_output_scale;
uniform float u_north;  // 0: east tangent, 1: north tangent (ibl::BlurAxis)
uniform float u_step_rad;
uniform float u_sigma_rad;

void main() {
  vec3 n = normalize(u_face_center + (2.0 * v_face_st.x - 1.0) * u_face_s_axis +
                     (2.0 * v_face_st.y - 1.0) * u_face_t_axis);
  vec3 across_meridian = vec3(-n.y, n.x, 0.0);  // cross(+Z, n)
  vec3 east = length(across_meridian) < 1e-4 ? vec3(1.0, 0.0, 0.0) : normalize(across_meridian);
  vec3 tangent = u_north > 0.5 ? cross(n, east) : east;
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  float inverse_two_sigma2 = 1.0 / (2.0 * u_sigma_rad * u_sigma_rad);
  for (int i = -HALF_TAPS; i <= HALF_TAPS; ++i) {
    float angle = float(i) * u_step_rad;
    float weight = exp(-angle * angle * inverse_two_sigma2);
    vec3 direction = cos(angle) * n + sin(angle) * tangent;
    sum += weight * sampleCubeBilinear(u_input, direction, u_input_face_size, u_input_scale);
    weight_sum += weight;
  }
  vec4 blurred = sum / weight_sum;
  gl_FragColor = encodeCubeTexel(blurred.rgb, blurred.a, u_output_scale);
}
