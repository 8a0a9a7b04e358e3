#version 100
// Stage 3: the diffuse map as E(n) / pi by two cosine passes on the sphere of
// directions, the maths of ibl::irradianceOverPiByCosinePasses (see the long
// comments in src/ibl/spherical_blur.hpp). One file, three programs, picked
// by a #define:
//   PREFILTER_PASS  reflection map -> prefiltered map: each output texel is
//                   the solid-angle-weighted mean of a PREFILTER_FACTOR^2
//                   block (ibl::downsampleCubeMap), rgb premultiplied by
//                   validity, alpha = mean validity;
//   EAST_PASS       prefiltered -> intermediate: cos^2 kernel along the east
//                   tangent, 2 HALF_TAPS + 1 taps at i pi / (2 HALF_TAPS + 1);
//   NORTH_PASS      intermediate -> diffuse: cos kernel along the north
//                   tangent; taps within u_pole_cosine of +-Z integrate their
//                   east circle directly from the prefiltered map with the
//                   output texel's own east tangent (the pole correction);
//                   then rgb / alpha (normalised convolution; alpha <= 1e-6:
//                   rgb 0), alpha = the blurred validity (coverage), blended
//                   with the previous map (diffuse_blend.glsl).
// The prefiltered and intermediate maps hold (validity * radiance, validity),
// so every pass is the same weighted sum on all four channels. Taps run along
// great circles, so nothing depends on cube face edges; every lookup is
// sampleCubeBilinear (per-face bilinear on decoded values, as
// ibl::CubeMapRGB::sampleBilinear).
#include "color_transfer.glsl"
#include "cube_storage.glsl"

#ifndef HALF_TAPS
#define HALF_TAPS 16
#endif
#ifndef PREFILTER_FACTOR
#define PREFILTER_FACTOR 4
#endif
// ibl::blurTapAngleRad for the cosine kernels: centres of 2 HALF_TAPS + 1
// equal cells of [-pi/2, pi/2].
#define TAP_STEP_RAD (3.14159265358979 / (2.0 * float(HALF_TAPS) + 1.0))

varying vec2 v_face_st;

uniform vec3 u_face_center;
uniform vec3 u_face_s_axis;
uniform vec3 u_face_t_axis;
uniform samplerCube u_input;
uniform float u_input_face_size;
uniform float u_input_scale;
uniform float u_output_scale;

vec3 texelDirection() {
  return normalize(u_face_center + (2.0 * v_face_st.x - 1.0) * u_face_s_axis +
                   (2.0 * v_face_st.y - 1.0) * u_face_t_axis);
}

// ibl::blurTangent(n, kEast): cross(+Z, n) normalised; +X at the poles.
vec3 eastTangent(vec3 n) {
  vec3 across_meridian = vec3(-n.y, n.x, 0.0);
  return length(across_meridian) < 1e-4 ? vec3(1.0, 0.0, 0.0) : normalize(across_meridian);
}

#if defined(PREFILTER_PASS)

uniform float u_face_index;     // 0..5, GL order
uniform float u_output_face_size;

void main() {
  vec2 block = floor(v_face_st * u_output_face_size) * float(PREFILTER_FACTOR);
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int dy = 0; dy < PREFILTER_FACTOR; ++dy) {
    for (int dx = 0; dx < PREFILTER_FACTOR; ++dx) {
      vec2 texel = block + vec2(float(dx), float(dy));
      // Solid angle of the texel up to a constant: the density
      // (1 + u^2 + v^2)^(-3/2) at its centre. ibl::cubeTexelSolidAngle is the
      // exact integral (a difference of four atan2 of O(1), which fp32 would
      // resolve to ~1e-3 relative and mediump not at all); within a 4x4
      // block the two normalised weights differ by < 1e-4 relative
      // (tests/gles/cosine_irradiance_test.cpp computes the bound).
      vec2 c = 2.0 * (texel + 0.5) / u_input_face_size - 1.0;
      float q = 1.0 + dot(c, c);
      float weight = 1.0 / (q * sqrt(q));
      vec4 t = fetchCubeTexel(u_input, u_face_index, texel, u_input_face_size, u_input_scale);
      sum += weight * vec4(t.rgb * t.a, t.a);
      weight_sum += weight;
    }
  }
  vec4 mean = sum / weight_sum;
  gl_FragColor = encodeCubeTexel(mean.rgb, mean.a, u_output_scale);
}

#elif defined(EAST_PASS)

void main() {
  vec3 n = texelDirection();
  vec3 east = eastTangent(n);
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int i = -HALF_TAPS; i <= HALF_TAPS; ++i) {
    float angle = float(i) * TAP_STEP_RAD;
    float c = cos(angle);
    float weight = c * c;
    sum += weight * sampleCubeBilinear(u_input, c * n + sin(angle) * east, u_input_face_size, u_input_scale);
    weight_sum += weight;
  }
  vec4 mean = sum / weight_sum;
  gl_FragColor = encodeCubeTexel(mean.rgb, mean.a, u_output_scale);
}

#elif defined(NORTH_PASS)

#include "diffuse_blend.glsl"

uniform samplerCube u_prefiltered;  // for the taps near the poles
uniform float u_prefiltered_face_size;
uniform float u_prefiltered_scale;
uniform float u_pole_cosine;  // cos(pole_direct_deg)

void main() {
  vec3 n = texelDirection();
  vec3 east = eastTangent(n);
  vec3 north = cross(n, east);
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int j = -HALF_TAPS; j <= HALF_TAPS; ++j) {
    float angle = float(j) * TAP_STEP_RAD;
    vec3 d = cos(angle) * n + sin(angle) * north;
    vec4 inner;
    if (abs(d.z) > u_pole_cosine) {
      // Near +-Z the intermediate texels were integrated along east circles
      // of every orientation; integrate this one's own circle instead.
      inner = vec4(0.0);
      float inner_weight_sum = 0.0;
      for (int i = -HALF_TAPS; i <= HALF_TAPS; ++i) {
        float b = float(i) * TAP_STEP_RAD;
        float c = cos(b);
        float w = c * c;
        inner += w * sampleCubeBilinear(u_prefiltered, c * d + sin(b) * east, u_prefiltered_face_size,
                                        u_prefiltered_scale);
        inner_weight_sum += w;
      }
      inner /= inner_weight_sum;
    } else {
      inner = sampleCubeBilinear(u_input, d, u_input_face_size, u_input_scale);
    }
    float weight = cos(angle);
    sum += weight * inner;
    weight_sum += weight;
  }
  sum /= weight_sum;
  // Normalised convolution; a footprint that saw nothing at all stays 0.
  vec4 fresh = sum.a > 1e-6 ? vec4(sum.rgb / sum.a, sum.a) : vec4(0.0, 0.0, 0.0, max(sum.a, 0.0));
  vec4 blended = blendWithPrevious(fresh, n);
  gl_FragColor = encodeCubeTexel(blended.rgb, blended.a, u_output_scale);
}

#endif
