#version 100
// Stage 4: ibl::shadeSurface in linear light, then sRGB-encoded (clamped).
// The reflection term reads the ladder mirror, glossy 0..L-1, diffuse
// (src/ibl/surface_shading.hpp) between the two rungs nearest to
// u_glossiness; samplers of absent glossy levels are bound to a valid cube
// map and never read.
#include "color_transfer.glsl"
#include "cube_storage.glsl"

varying vec3 v_normal_w;
varying vec3 v_to_eye_w;

uniform samplerCube u_diffuse_map;
uniform float u_diffuse_face_size;
uniform float u_diffuse_scale;
uniform samplerCube u_reflection_map;
uniform float u_reflection_face_size;
uniform float u_reflection_scale;
uniform samplerCube u_glossy0_map;
uniform float u_glossy0_face_size;
uniform float u_glossy0_scale;
uniform samplerCube u_glossy1_map;
uniform float u_glossy1_face_size;
uniform float u_glossy1_scale;
uniform float u_glossy_levels;  // L: 0, 1 or 2
uniform float u_glossiness;

uniform vec3 u_albedo;
uniform float u_material_ambient;
uniform float u_k_diffuse;
uniform float u_k_specular;
uniform float u_shininess;
uniform float u_k_reflect;
uniform vec3 u_ambient_rgb;
uniform vec3 u_highlight_direction_w;
uniform vec3 u_highlight_rgb;
// ibl::SceneLighting's clipped lights: the energy the 8-bit ball lost to
// clipping, added to the diffuse term (E / pi, at most a few tens: mediump
// holds it).
uniform vec3 u_clipped_direction_w[4];
uniform vec3 u_clipped_diffuse_rgb[4];

// Rung k of the ladder: 0 mirror, 1..L glossy (at the mirror direction), L + 1 diffuse (at the normal).
vec3 rung(float k, vec3 mirror, vec3 diffuse) {
  if (k > u_glossy_levels + 0.5) return diffuse;
  if (k < 0.5) return sampleCubeBilinear(u_reflection_map, mirror, u_reflection_face_size, u_reflection_scale).rgb;
  if (k < 1.5) return sampleCubeBilinear(u_glossy0_map, mirror, u_glossy0_face_size, u_glossy0_scale).rgb;
  return sampleCubeBilinear(u_glossy1_map, mirror, u_glossy1_face_size, u_glossy1_scale).rgb;
}

void main() {
  vec3 n = normalize(v_normal_w);
  vec3 to_eye = normalize(v_to_eye_w);
  vec3 half_vector = normalize(u_highlight_direction_w + to_eye);
  float n_dot_h = max(dot(n, half_vector), 0.0);
  float highlight = n_dot_h > 0.0 ? pow(n_dot_h, u_shininess) : 0.0;
  vec3 mirror = reflect(-to_eye, n);
  vec3 diffuse = sampleCubeBilinear(u_diffuse_map, n, u_diffuse_face_size, u_diffuse_scale).rgb;
  for (int k = 0; k < 4; ++k) diffuse += u_clipped_diffuse_rgb[k] * max(dot(n, u_clipped_direction_w[k]), 0.0);
  // ibl::reflectionLadderBlend: exact at glossiness 0 and 1, where the other rung is not read.
  float position = (1.0 - clamp(u_glossiness, 0.0, 1.0)) * (u_glossy_levels + 1.0);
  float lower = floor(position);
  float toward_next = position - lower;
  vec3 reflection = rung(lower, mirror, diffuse);
  if (toward_next > 0.0) reflection = mix(reflection, rung(lower + 1.0, mirror, diffuse), toward_next);
  vec3 color = u_ambient_rgb * u_material_ambient + u_k_diffuse * diffuse * u_albedo +
               u_k_specular * u_highlight_rgb * highlight + u_k_reflect * reflection;
  gl_FragColor = vec4(linearToSrgb(color), 1.0);
}
