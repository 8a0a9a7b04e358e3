#version 100
// Stage 4: ibl::shadeSurface in linear light, then through the camera's
// response (camera_response.glsl: its transfer, and its noise when matched).
// The reflection term reads the ladder mirror, glossy 0..L-1, diffuse
// (src/ibl/surface_shading.hpp) between the two rungs nearest to the
// material's glossiness. Which two is fixed when the program is built:
// REFLECTION_LOWER_RUNG, and REFLECTION_UPPER_RUNG when the blend reads a
// second one (0 mirror, 1 glossy 0, 2 glossy 1, 3 diffuse; ObjectCompositor
// picks them with ibl::reflectionLadderBlend). A uniform branch would skip
// the rest on most GPUs, but some run every side of a branch, masked
// (llvmpipe does), and each lookup is four cube reads: choosing at build
// time halved this pass there. Samplers of rungs not read are still bound
// to a valid cube map.
#include "color_transfer.glsl"
#include "camera_transfer.glsl"
#include "camera_response.glsl"
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
uniform float u_toward_upper_rung;  // the upper rung's weight, in (0, 1)

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
uniform vec3 u_lamp_direction_w;  // a virtual lamp, seen from the object's middle (ibl::SceneLighting)
uniform vec3 u_lamp_diffuse_rgb;

#ifndef REFLECTION_LOWER_RUNG
#define REFLECTION_LOWER_RUNG 0
#endif

// The ladder's rungs by kind: the mirror and glossy maps at the mirror
// direction, the diffuse map at the normal (already looked up).
vec3 ladderRung(int kind, vec3 mirror, vec3 diffuse) {
  if (kind == 0) return sampleCubeBilinear(u_reflection_map, mirror, u_reflection_face_size, u_reflection_scale).rgb;
  if (kind == 1) return sampleCubeBilinear(u_glossy0_map, mirror, u_glossy0_face_size, u_glossy0_scale).rgb;
  if (kind == 2) return sampleCubeBilinear(u_glossy1_map, mirror, u_glossy1_face_size, u_glossy1_scale).rgb;
  return diffuse;
}

void main() {
  vec3 n = normalize(v_normal_w);
  vec3 to_eye = normalize(v_to_eye_w);
  vec3 half_vector = normalize(u_highlight_direction_w + to_eye);
  // pow(n.h, shininess) written as exp(shininess ln(1 - x)) with
  // x = 1 - n.h = |n - h|^2 / 2 (n and h unit): near the peak, where a sharp
  // highlight lives, x keeps its own relative precision, while n.h, a number
  // next to 1, keeps only 2^-11 at 16-bit mediump, an error the power
  // multiplies by the shininess (a shininess-4096 highlight came out 69
  // levels off, tests/gles/mediump_test.cpp). ln(1 - x) is its series below
  // x = 1/4 (the first term left out, x^7 / 7, is under 4e-5 of the sum);
  // further out pow(n.h) is accurate.
  vec3 n_minus_h = n - half_vector;
  float x = 0.5 * dot(n_minus_h, n_minus_h);
  float ln_n_dot_h = -x * (1.0 + x * (0.5 + x * (1.0 / 3.0 + x * (0.25 + x * (0.2 + x * (1.0 / 6.0))))));
  float n_dot_h = 1.0 - x;
  float highlight = x < 0.25 ? exp(u_shininess * ln_n_dot_h) : (n_dot_h > 0.0 ? pow(n_dot_h, u_shininess) : 0.0);
  vec3 mirror = reflect(-to_eye, n);
  vec3 diffuse = sampleCubeBilinear(u_diffuse_map, n, u_diffuse_face_size, u_diffuse_scale).rgb;
  for (int k = 0; k < 4; ++k) diffuse += u_clipped_diffuse_rgb[k] * max(dot(n, u_clipped_direction_w[k]), 0.0);
  diffuse += u_lamp_diffuse_rgb * max(dot(n, u_lamp_direction_w), 0.0);
  // ladderRung's kind is a constant here, so the compiler keeps only that
  // rung's lookup.
  vec3 reflection = ladderRung(REFLECTION_LOWER_RUNG, mirror, diffuse);
#ifdef REFLECTION_UPPER_RUNG
  reflection = mix(reflection, ladderRung(REFLECTION_UPPER_RUNG, mirror, diffuse), u_toward_upper_rung);
#endif
  vec3 color = u_ambient_rgb * u_material_ambient + u_k_diffuse * diffuse * u_albedo +
               u_k_specular * u_highlight_rgb * highlight + u_k_reflect * reflection;
  gl_FragColor = vec4(cameraOutput(color), 1.0);
}
