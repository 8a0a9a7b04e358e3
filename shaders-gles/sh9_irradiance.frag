#version 100
// The diffuse map from nine spherical-harmonics coefficients (Ramamoorthi &
// Hanrahan's irradiance, ibl::sh9DiffuseMap): each texel stores
// max(0, E(n)) / pi, alpha 1 (the fit covers every direction).
//
// u_sh holds ibl::sh9DiffusePolynomial, folded on the CPU in double: the R&H
// constants and 1/pi are already in, so the shader evaluates
//   p0 + p1 x + p2 y + p3 z + p4 xy + p5 yz + p6 xz + p7 z^2 + p8 (x^2 - y^2)
// with every monomial in [-1, 1]. In mediump (10-bit mantissa) each term's
// rounding is then relative to its coefficient and the total error stays
// below 14 * 2^-11 * sum |p_k| (tests/ibl/spherical_harmonics_test.cpp
// emulates it: under 1.4 8-bit levels for a near-delta light).
#include "color_transfer.glsl"
#include "cube_storage.glsl"
#include "diffuse_blend.glsl"

varying vec2 v_face_st;

uniform vec3 u_face_center;
uniform vec3 u_face_s_axis;
uniform vec3 u_face_t_axis;
uniform vec3 u_sh[9];
uniform float u_output_scale;

void main() {
  vec3 n = normalize(u_face_center + (2.0 * v_face_st.x - 1.0) * u_face_s_axis +
                     (2.0 * v_face_st.y - 1.0) * u_face_t_axis);
  vec3 e = u_sh[0] + u_sh[1] * n.x + u_sh[2] * n.y + u_sh[3] * n.z + u_sh[4] * (n.x * n.y) +
           u_sh[5] * (n.y * n.z) + u_sh[6] * (n.x * n.z) + u_sh[7] * (n.z * n.z) +
           u_sh[8] * (n.x * n.x - n.y * n.y);
  // Band-limited ringing can dip below 0 opposite a bright small light;
  // light is never negative (and the 8-bit storage clamps anyway).
  vec4 blended = blendWithPrevious(vec4(max(e, vec3(0.0)), 1.0), n);
  gl_FragColor = encodeCubeTexel(blended.rgb, blended.a, u_output_scale);
}
