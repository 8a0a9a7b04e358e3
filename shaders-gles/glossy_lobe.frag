#version 100
// Glossy maps: the reflection map convolved with a normalised cos^n lobe,
// the maths of ibl::glossyMap (derivation in src/ibl/glossy_maps.hpp). The
// prefilter is cosine_irradiance.frag's PREFILTER_PASS; this file has the
// two lobe passes, picked by a #define:
//   EAST_PASS   prefiltered -> intermediate: kernel cos^(n+1) (the extra
//               cos is the solid angle) along the east tangent;
//   NORTH_PASS  intermediate -> glossy map: kernel cos^n along the north
//               tangent, taps within u_pole_cosine of +-Z integrating their
//               east circle directly from the prefiltered map (the pole
//               correction), then rgb / alpha (normalised convolution),
//               alpha = the blurred validity.
// 2 HALF_TAPS + 1 taps a pass at i * u_tap_step_rad (3 sigma / HALF_TAPS).
// Weights are exp(-power * s(a)), s the series of -ln cos a to a^10
// (ibl::glossyTapWeight): all terms positive, so it keeps its accuracy in
// mediump, where pow(cos(a), 129) would amplify cos's rounding 129 times.
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
uniform float u_tap_step_rad;
uniform float u_east_power;   // n + 1
uniform float u_north_power;  // n

vec3 texelDirection() {
  return normalize(u_face_center + (2.0 * v_face_st.x - 1.0) * u_face_s_axis +
                   (2.0 * v_face_st.y - 1.0) * u_face_t_axis);
}

// ibl::blurTangent(n, kEast): cross(+Z, n) normalised; +X at the poles.
vec3 eastTangent(vec3 n) {
  vec3 across_meridian = vec3(-n.y, n.x, 0.0);
  return length(across_meridian) < 1e-4 ? vec3(1.0, 0.0, 0.0) : normalize(across_meridian);
}

float lobeWeight(float power, float a) {
  float a2 = a * a;
  float s = a2 * (0.5 + a2 * (1.0 / 12.0 + a2 * (1.0 / 45.0 + a2 * (17.0 / 2520.0 + a2 * (31.0 / 14175.0)))));
  return exp(-power * s);
}

// sum_i w_i map(cos a_i d + sin a_i t) / sum_i w_i, the east kernel.
vec4 eastIntegral(samplerCube map, float face_size, float scale, vec3 d, vec3 t) {
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int i = -HALF_TAPS; i <= HALF_TAPS; ++i) {
    float a = float(i) * u_tap_step_rad;
    float w = lobeWeight(u_east_power, a);
    sum += w * sampleCubeBilinear(map, cos(a) * d + sin(a) * t, face_size, scale);
    weight_sum += w;
  }
  return sum / weight_sum;
}

#if defined(EAST_PASS)

void main() {
  vec3 n = texelDirection();
  vec4 mean = eastIntegral(u_input, u_input_face_size, u_input_scale, n, eastTangent(n));
  gl_FragColor = encodeCubeTexel(mean.rgb, mean.a, u_output_scale);
}

#elif defined(NORTH_PASS)

uniform samplerCube u_prefiltered;  // for the taps near the poles
uniform float u_prefiltered_face_size;
uniform float u_prefiltered_scale;
uniform float u_pole_cosine;  // cos(pole_direct_deg)

void main() {
  vec3 r = texelDirection();
  vec3 east = eastTangent(r);
  vec3 north = cross(r, east);
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int j = -HALF_TAPS; j <= HALF_TAPS; ++j) {
    float b = float(j) * u_tap_step_rad;
    vec3 d = cos(b) * r + sin(b) * north;
    // Near +-Z the intermediate texels were integrated along east circles
    // of every orientation; integrate this tap's own circle instead.
    vec4 inner = abs(d.z) > u_pole_cosine
                     ? eastIntegral(u_prefiltered, u_prefiltered_face_size, u_prefiltered_scale, d, east)
                     : sampleCubeBilinear(u_input, d, u_input_face_size, u_input_scale);
    float w = lobeWeight(u_north_power, b);
    sum += w * inner;
    weight_sum += w;
  }
  sum /= weight_sum;
  // Normalised convolution; a footprint that saw nothing at all stays 0.
  vec4 fresh = sum.a > 1e-6 ? vec4(sum.rgb / sum.a, sum.a) : vec4(0.0, 0.0, 0.0, max(sum.a, 0.0));
  gl_FragColor = encodeCubeTexel(fresh.rgb, fresh.a, u_output_scale);
}

#endif
