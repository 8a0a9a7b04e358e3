#version 100
// Stage 3: the diffuse map as E(n) / pi by two cosine passes on the sphere of
// directions, the maths of ibl::irradianceOverPiByCosinePasses (see the long
// comments in src/ibl/spherical_blur.hpp). One file, four programs, picked
// by a #define:
//   PREFILTER_PASS  reflection map -> prefiltered map: each output texel is
//                   the solid-angle-weighted mean of a PREFILTER_FACTOR^2
//                   block (ibl::downsampleCubeMap), rgb premultiplied by
//                   validity, alpha = mean validity;
//   EAST_PASS       prefiltered cube -> east latitude-longitude map
//                   (ibl::eastPassToLatLong): cos^2 kernel along the east
//                   tangent, 2 HALF_TAPS + 1 taps at i pi / (2 HALF_TAPS + 1);
//   NORTH_PASS      east map -> north latitude-longitude map
//                   (ibl::northPassOnLatLong): cos kernel along the texel's
//                   column, LATLONG_ROWS + 1 taps one row apart, folded over
//                   the poles; every tap is a texel centre;
//   RESAMPLE_PASS   north map -> diffuse cube (ibl::latLongToCube): one
//                   bilinear lookup per texel, then rgb / alpha (normalised
//                   convolution; alpha <= 1e-6: rgb 0), alpha = the blurred
//                   validity (coverage), blended with the previous map
//                   (diffuse_blend.glsl).
// The prefiltered and latitude-longitude maps hold (validity * radiance,
// validity), so every pass is the same weighted sum on all four channels.
// Cube lookups are sampleCubeBilinear (per-face bilinear on decoded values,
// as ibl::CubeMapRGB::sampleBilinear); latitude-longitude lookups decode
// texels fetched at their centres (NEAREST storage, as the cubes).
#include "color_transfer.glsl"
#include "cube_storage.glsl"

#ifndef HALF_TAPS
#define HALF_TAPS 16
#endif
#ifndef PREFILTER_FACTOR
#define PREFILTER_FACTOR 4
#endif
#ifndef LATLONG_ROWS
#define LATLONG_ROWS 32
#endif
#define LATLONG_COLUMNS (2.0 * float(LATLONG_ROWS))
#define PI 3.14159265358979
// ibl::blurTapAngleRad for the cosine kernels: centres of 2 HALF_TAPS + 1
// equal cells of [-pi/2, pi/2].
#define TAP_STEP_RAD (PI / (2.0 * float(HALF_TAPS) + 1.0))

varying vec2 v_face_st;

uniform vec3 u_face_center;
uniform vec3 u_face_s_axis;
uniform vec3 u_face_t_axis;
uniform samplerCube u_input;
uniform float u_input_face_size;
uniform float u_input_scale;
uniform float u_output_scale;

// Texel (column, row) of a latitude-longitude map, decoded.
vec4 fetchLatLongTexel(sampler2D map, vec2 texel, float linear_scale) {
  return decodeCubeTexel(texture2D(map, (texel + 0.5) / vec2(LATLONG_COLUMNS, float(LATLONG_ROWS))), linear_scale);
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

// Output: the latitude-longitude map; v_face_st = ((x + 0.5) / columns,
// (y + 0.5) / rows) is the texel's (phi / 2 pi, theta / pi).
void main() {
  float theta = PI * v_face_st.y;
  float phi = 2.0 * PI * v_face_st.x;
  vec3 d = vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
  vec3 east = vec3(-sin(phi), cos(phi), 0.0);  // cross(+Z, d) / sin(theta)
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int i = -HALF_TAPS; i <= HALF_TAPS; ++i) {
    float angle = float(i) * TAP_STEP_RAD;
    float c = cos(angle);
    float weight = c * c;
    sum += weight * sampleCubeBilinear(u_input, c * d + sin(angle) * east, u_input_face_size, u_input_scale);
    weight_sum += weight;
  }
  vec4 mean = sum / weight_sum;
  gl_FragColor = encodeCubeTexel(mean.rgb, mean.a, u_output_scale);
}

#elif defined(NORTH_PASS)

uniform sampler2D u_latlong;

void main() {
  vec2 texel = floor(v_face_st * vec2(LATLONG_COLUMNS, float(LATLONG_ROWS)));
  vec4 sum = vec4(0.0);
  float weight_sum = 0.0;
  for (int j = -LATLONG_ROWS / 2; j <= LATLONG_ROWS / 2; ++j) {
    float row = texel.y + float(j);
    float column = texel.x;
    if (row < 0.0 || row > float(LATLONG_ROWS) - 0.5) {
      // Over a pole: the mirrored row of the opposite meridian.
      row = row < 0.0 ? -row - 1.0 : 2.0 * float(LATLONG_ROWS) - row - 1.0;
      column = mod(column + float(LATLONG_ROWS), LATLONG_COLUMNS);
    }
    float weight = cos(float(j) * (PI / float(LATLONG_ROWS)));
    sum += weight * fetchLatLongTexel(u_latlong, vec2(column, row), u_input_scale);
    weight_sum += weight;
  }
  vec4 mean = sum / weight_sum;
  gl_FragColor = encodeCubeTexel(mean.rgb, mean.a, u_output_scale);
}

#elif defined(RESAMPLE_PASS)

#include "diffuse_blend.glsl"

uniform sampler2D u_latlong;

vec3 texelDirection() {
  return normalize(u_face_center + (2.0 * v_face_st.x - 1.0) * u_face_s_axis +
                   (2.0 * v_face_st.y - 1.0) * u_face_t_axis);
}

// ibl::LatLongRGB::sampleBilinear for theta in [0, pi]: wraps in phi,
// clamps to the first and last rows' centres.
vec4 sampleLatLongBilinear(sampler2D map, float theta, float phi, float linear_scale) {
  float rows = float(LATLONG_ROWS);
  vec2 uv = vec2(phi / (2.0 * PI) * LATLONG_COLUMNS - 0.5, clamp(theta / PI * rows - 0.5, 0.0, rows - 1.0));
  vec2 base = floor(uv);
  vec2 f = uv - base;
  float x0 = mod(base.x, LATLONG_COLUMNS);
  float x1 = mod(base.x + 1.0, LATLONG_COLUMNS);
  float y1 = min(base.y + 1.0, rows - 1.0);
  vec4 top = mix(fetchLatLongTexel(map, vec2(x0, base.y), linear_scale),
                 fetchLatLongTexel(map, vec2(x1, base.y), linear_scale), f.x);
  vec4 bottom = mix(fetchLatLongTexel(map, vec2(x0, y1), linear_scale),
                    fetchLatLongTexel(map, vec2(x1, y1), linear_scale), f.x);
  return mix(top, bottom, f.y);
}

void main() {
  vec3 n = texelDirection();
  // atan rather than acos(n.z): acos loses half the digits near the poles.
  vec4 sum = sampleLatLongBilinear(u_latlong, atan(length(n.xy), n.z), atan(n.y, n.x), u_input_scale);
  // Normalised convolution; a footprint that saw nothing at all stays 0.
  vec4 fresh = sum.a > 1e-6 ? vec4(sum.rgb / sum.a, sum.a) : vec4(0.0, 0.0, 0.0, max(sum.a, 0.0));
  vec4 blended = blendWithPrevious(fresh, n);
  gl_FragColor = encodeCubeTexel(blended.rgb, blended.a, u_output_scale);
}

#endif
