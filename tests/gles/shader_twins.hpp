// CPU twins of the fragment shaders in shaders-gles/, statement for
// statement, templated on the precision of their arithmetic (glsl_precision.hpp):
// float is what a GPU with fragment highp computes, glsl::Mediump16 what a
// GPU without it computes (every value then mediump, a 16-bit float on many
// GLES2 GPUs). tests/gles/mediump_test.cpp runs the GPU tests' inputs through
// both and checks the float twin against the GPU itself, so a twin that
// drifts from its shader fails there.
//
// What the twins take from the fixed-function hardware, in double: texture
// filtering (the sampler gets the S-valued coordinate; its own filter
// arithmetic is the hardware's), the varyings' interpolation (rounded to S
// when the shader reads them) and the render target's storage (RGBA8 or half
// floats). Uniforms are rounded to S, as a driver converts them.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include <glm/glm.hpp>

#include "glsl_precision.hpp"
#include "ibl/cube_map.hpp"

namespace probelight::twin {

using glsl::vec2;
using glsl::vec3;
using glsl::vec4;

template <class S> vec2<S> toS(const glm::dvec2& v) { return {S(v.x), S(v.y)}; }
template <class S> vec3<S> toS(const glm::dvec3& v) { return {S(v.x), S(v.y), S(v.z)}; }
template <class S> vec4<S> toS(const glm::dvec4& v) { return {S(v.x), S(v.y), S(v.z), S(v.w)}; }
template <class V> glm::dvec4 toDouble(const V& v) {
  return {double(v.x), double(v.y), double(v.z), double(v.w)};
}

// ---- Textures as the samplers see them -------------------------------------

// A 2D texture's texels as the sampler returns them (normalised bytes or
// half floats), CLAMP_TO_EDGE, LINEAR or NEAREST.
struct Texture2D {
  int width = 0, height = 0;
  bool linear = false;
  std::vector<glm::vec4> texels;  // row-major, row 0 first (t = 0)
  glm::vec4 at(int x, int y) const {
    x = std::clamp(x, 0, width - 1);
    y = std::clamp(y, 0, height - 1);
    return texels[static_cast<size_t>(y) * width + x];
  }
};

template <class S> vec4<S> texture2D(const Texture2D& t, vec2<S> coord) {
  const double u = double(coord.x) * t.width, v = double(coord.y) * t.height;
  glm::dvec4 value;
  if (!t.linear) {
    value = glm::dvec4(t.at(static_cast<int>(std::floor(u)), static_cast<int>(std::floor(v))));
  } else {
    const double x = u - 0.5, y = v - 0.5;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    value = (1 - fy) * ((1 - fx) * glm::dvec4(t.at(x0, y0)) + fx * glm::dvec4(t.at(x0 + 1, y0))) +
            fy * ((1 - fx) * glm::dvec4(t.at(x0, y0 + 1)) + fx * glm::dvec4(t.at(x0 + 1, y0 + 1)));
  }
  return toS<S>(value);
}

// A NEAREST cube map (all of probelight's are), faces in GL order.
struct TextureCube {
  int face_size = 0;
  std::array<std::vector<glm::vec4>, 6> faces;
};

template <class S> vec4<S> textureCube(const TextureCube& t, vec3<S> direction) {
  const ibl::CubeTexelCoord c = ibl::directionToCubeCoord({double(direction.x), double(direction.y), double(direction.z)});
  const int n = t.face_size;
  const int x = std::clamp(static_cast<int>(std::floor(c.s * n)), 0, n - 1);
  const int y = std::clamp(static_cast<int>(std::floor(c.t * n)), 0, n - 1);
  return toS<S>(glm::dvec4(t.faces[static_cast<size_t>(c.face)][static_cast<size_t>(y) * n + x]));
}

// What a render target keeps of gl_FragColor.
enum class Storage { kRgba8, kHalfFloat };

inline glm::vec4 stored(const glm::dvec4& color, Storage storage) {
  glm::vec4 out;
  for (int c = 0; c < 4; ++c) {
    if (storage == Storage::kRgba8) {
      const double x = std::isnan(color[c]) ? 0.0 : std::clamp(color[c], 0.0, 1.0);
      out[c] = static_cast<float>(std::nearbyint(x * 255.0) / 255.0);
    } else {
      out[c] = static_cast<float>(glsl::roundToHalf(color[c]));
    }
  }
  return out;
}

// ---- color_transfer.glsl ----------------------------------------------------

template <class S> vec3<S> srgbToLinear(vec3<S> encoded) {
  vec3<S> c = clamp(encoded, S(0.0), S(1.0));
  vec3<S> low = c * S(1.0 / 12.92);
  vec3<S> x = c * S(1.0 / 1.055) + S(0.055 / 1.055);
  vec3<S> s = sqrt(x);
  vec3<S> u = s - S(0.650394426);
  vec3<S> x_pow_minus_tenth =
      ((((S(-0.803481682) * u + S(0.610555156)) * u - S(0.336195787)) * u + S(0.300160814)) * u - S(0.335218796)) * u +
      S(1.08990671);
  vec3<S> high = x * x * s * x_pow_minus_tenth;
  return mix(high, low, step(c, vec3<S>(S(0.04045))));
}

template <class S> vec3<S> linearToSrgb(vec3<S> linear) {
  vec3<S> l = clamp(linear, S(0.0), S(1.0));
  vec3<S> low = S(12.92) * l;
  vec3<S> high = S(1.055) * pow(l, vec3<S>(S(1.0 / 2.4))) - S(0.055);
  return mix(high, low, step(l, vec3<S>(S(0.0031308))));
}

// ---- camera_projection.glsl -------------------------------------------------

template <class S> vec2<S> distortNormalized(vec2<S> p, vec4<S> k, S k3) {
  S r2 = dot(p, p);
  S radial = S(1.0) + r2 * (k.x + r2 * (k.y + r2 * k3));
  S p1 = k.z;
  S p2 = k.w;
  return {p.x * radial + S(2.0) * p1 * p.x * p.y + p2 * (r2 + S(2.0) * p.x * p.x),
          p.y * radial + p1 * (r2 + S(2.0) * p.y * p.y) + S(2.0) * p2 * p.x * p.y};
}

template <class S>
vec2<S> distortionDelta(vec2<S> c, vec2<S> d, S center_r2, S center_radial, vec4<S> k, S k3) {
  vec2<S> p = c + d;
  S r2_delta = dot(d, c + p);
  S r2 = center_r2 + r2_delta;
  S radial_delta = r2_delta * (k.x + k.y * (r2 + center_r2) + k3 * (r2 * r2 + r2 * center_r2 + center_r2 * center_r2));
  S p1 = k.z;
  S p2 = k.w;
  S xy_delta = d.x * p.y + c.x * d.y;
  vec2<S> squares_delta = d * (c + p);
  return d * (center_radial + radial_delta) + c * radial_delta +
         vec2<S>(S(2.0) * p1 * xy_delta + p2 * (r2_delta + S(2.0) * squares_delta.x),
                 p1 * (r2_delta + S(2.0) * squares_delta.y) + S(2.0) * p2 * xy_delta);
}

// ---- cube_storage.glsl ------------------------------------------------------

template <class S> vec4<S> encodeCubeTexel(vec3<S> linear, S validity, S linear_scale, bool srgb8) {
  if (srgb8) return {linearToSrgb(linear / linear_scale), validity};
  return {linear, validity};
}

template <class S> vec4<S> decodeCubeTexel(vec4<S> stored_texel, S linear_scale, bool srgb8) {
  if (srgb8) return {srgbToLinear(stored_texel.rgb()) * linear_scale, stored_texel.w};
  return stored_texel;
}

template <class S> vec3<S> cubeFaceCoord(vec3<S> d) {
  vec3<S> a = abs(d);
  S face, sc, tc, ma;
  if (a.z >= a.x && a.z >= a.y) {
    ma = a.z;
    face = d.z >= S(0.0) ? S(4.0) : S(5.0);
    sc = d.z >= S(0.0) ? d.x : -d.x;
    tc = -d.y;
  } else if (a.y >= a.x) {
    ma = a.y;
    face = d.y >= S(0.0) ? S(2.0) : S(3.0);
    sc = d.x;
    tc = d.y >= S(0.0) ? d.z : -d.z;
  } else {
    ma = a.x;
    face = d.x >= S(0.0) ? S(0.0) : S(1.0);
    sc = d.x >= S(0.0) ? -d.z : d.z;
    tc = -d.y;
  }
  return {face, S(0.5) * (sc / ma + S(1.0)), S(0.5) * (tc / ma + S(1.0))};
}

template <class S> vec3<S> cubeFaceDirection(S face, vec2<S> st) {
  vec2<S> c = S(2.0) * st - S(1.0);
  if (face < S(0.5)) return {S(1.0), -c.y, -c.x};
  if (face < S(1.5)) return {S(-1.0), -c.y, c.x};
  if (face < S(2.5)) return {c.x, S(1.0), c.y};
  if (face < S(3.5)) return {c.x, S(-1.0), -c.y};
  if (face < S(4.5)) return {c.x, -c.y, S(1.0)};
  return {-c.x, -c.y, S(-1.0)};
}

template <class S>
vec4<S> fetchCubeTexel(const TextureCube& map, S face, vec2<S> texel, S face_size, S linear_scale, bool srgb8) {
  return decodeCubeTexel(textureCube(map, cubeFaceDirection(face, (texel + S(0.5)) / face_size)), linear_scale, srgb8);
}

template <class S>
vec4<S> sampleCubeBilinear(const TextureCube& map, vec3<S> direction, S face_size, S linear_scale, bool srgb8) {
  vec3<S> coord = cubeFaceCoord(direction);
  vec2<S> uv = vec2<S>(coord.y, coord.z) * face_size - S(0.5);
  vec2<S> base = floor(uv);
  vec2<S> f = uv - base;
  S last = face_size - S(1.0);
  vec2<S> lo = clamp(base, S(0.0), last);
  vec2<S> hi = clamp(base + S(1.0), S(0.0), last);
  vec4<S> top = mix(fetchCubeTexel(map, coord.x, {lo.x, lo.y}, face_size, linear_scale, srgb8),
                    fetchCubeTexel(map, coord.x, {hi.x, lo.y}, face_size, linear_scale, srgb8), f.x);
  vec4<S> bottom = mix(fetchCubeTexel(map, coord.x, {lo.x, hi.y}, face_size, linear_scale, srgb8),
                       fetchCubeTexel(map, coord.x, {hi.x, hi.y}, face_size, linear_scale, srgb8), f.x);
  return mix(top, bottom, f.y);
}

// ---- probe_to_cube.frag -----------------------------------------------------

// The uniforms as passes::probeToCubeUniforms computes them (in double),
// and the shader's compile-time choices.
struct ProbeToCubeInputs {
  glm::dvec3 eye_ball, eye_direction;
  glm::dvec2 center_normalized;
  double radius_over_depth;
  glm::dvec4 distortion;
  double distortion_k3;
  double center_r2, center_radial;
  glm::dvec2 focal_over_size, center_texcoord, center_texcoord_residual;
  double inverse_reflectance;
  double storage_scale;
  int normal_iterations = 1;
  bool srgb8 = true;
};

// texcoord_out (optional): where the camera texture was read.
template <class S>
vec4<S> probeToCube(const ProbeToCubeInputs& in, vec3<S> v_direction_cam, const Texture2D& camera,
                    glm::dvec2* texcoord_out = nullptr) {
  // PL_FRAGMENT_HIGHP only where the GPU has highp, i.e. at float here.
  const S blind_spot_length_squared = std::is_same_v<S, float> ? S(1e-12) : S(1e-6);
  const vec3<S> u_eye_ball = toS<S>(in.eye_ball), u_eye_direction = toS<S>(in.eye_direction);
  const S u_radius_over_depth = S(in.radius_over_depth);

  vec3<S> r = normalize(v_direction_cam);
  vec3<S> bisector = u_eye_direction + r;
  S length_squared = dot(bisector, bisector);
  bool blind = length_squared < blind_spot_length_squared;
  vec3<S> normal = bisector * glsl::inversesqrt(length_squared);
  for (int i = 0; i < in.normal_iterations; ++i) {
    vec3<S> to_eye = u_eye_ball - normal;
    S to_eye_squared = dot(to_eye, to_eye);
    bisector = to_eye + glsl::sqrt(to_eye_squared) * r;
    length_squared = dot(bisector, bisector);
    blind = blind || length_squared < blind_spot_length_squared * to_eye_squared;
    vec3<S> target = bisector * glsl::inversesqrt(length_squared);
    S relaxation = to_eye_squared / (to_eye_squared + S(0.5) * (dot(u_eye_ball, normal) - S(1.0)));
    normal += relaxation * (target - normal);
    normal *= S(1.5) - S(0.5) * dot(normal, normal);
  }
  blind = blind || dot(normal, u_eye_ball - normal) <= S(0.0);
  vec3<S> offset = u_radius_over_depth * normal;
  S depth_ratio = S(1.0) + offset.z;
  blind = blind || depth_ratio <= S(0.0);
  const vec2<S> u_center_normalized = toS<S>(in.center_normalized);
  vec2<S> normalized_delta = (offset.xy() - u_center_normalized * offset.z) / glsl::max(depth_ratio, S(1e-3));
  vec2<S> distorted_delta = distortionDelta(u_center_normalized, normalized_delta, S(in.center_r2),
                                            S(in.center_radial), toS<S>(in.distortion), S(in.distortion_k3));
  vec2<S> texcoord = toS<S>(in.center_texcoord) +
                     (distorted_delta * toS<S>(in.focal_over_size) + toS<S>(in.center_texcoord_residual));
  if (texcoord_out) *texcoord_out = {double(texcoord.x), double(texcoord.y)};
  vec3<S> linear = srgbToLinear(texture2D(camera, texcoord).rgb()) * S(in.inverse_reflectance);
  return blind ? vec4<S>(S(0.0)) : encodeCubeTexel(linear, S(1.0), S(in.storage_scale), in.srgb8);
}

// ---- cube_face.vert passes: rendering a whole target -----------------------

// Runs fragment(face, v_face_st) over every texel of a cube map's faces
// (v_face_st = texel centre, rounded to S as the shader reads it) and stores
// the results as the render target would.
template <class S, class Fragment> TextureCube renderCube(int face_size, Storage storage, Fragment fragment) {
  TextureCube out;
  out.face_size = face_size;
  for (int face = 0; face < 6; ++face) {
    out.faces[static_cast<size_t>(face)].resize(static_cast<size_t>(face_size) * face_size);
    for (int y = 0; y < face_size; ++y)
      for (int x = 0; x < face_size; ++x) {
        const vec2<S> st{S((x + 0.5) / face_size), S((y + 0.5) / face_size)};
        out.faces[static_cast<size_t>(face)][static_cast<size_t>(y) * face_size + x] =
            stored(toDouble(fragment(face, st)), storage);
      }
  }
  return out;
}

// The same over a latitude-longitude map (2 rows wide, NEAREST).
template <class S, class Fragment> Texture2D renderLatLong(int rows, Storage storage, Fragment fragment) {
  Texture2D out;
  out.width = 2 * rows;
  out.height = rows;
  out.texels.resize(static_cast<size_t>(out.width) * rows);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < out.width; ++x) {
      const vec2<S> st{S((x + 0.5) / out.width), S((y + 0.5) / rows)};
      out.texels[static_cast<size_t>(y) * out.width + x] = stored(toDouble(fragment(st)), storage);
    }
  return out;
}

// A face's axes (passes::kFaceBases), as the face uniforms.
struct FaceAxes {
  glm::dvec3 center, s_axis, t_axis;
};

template <class S> vec3<S> texelDirection(const FaceAxes& axes, vec2<S> v_face_st) {
  return normalize(toS<S>(axes.center) + (S(2.0) * v_face_st.x - S(1.0)) * toS<S>(axes.s_axis) +
                   (S(2.0) * v_face_st.y - S(1.0)) * toS<S>(axes.t_axis));
}

// ---- cosine_irradiance.frag -------------------------------------------------

struct CosineDefines {
  int half_taps = 16;
  int prefilter_factor = 4;
  int latlong_rows = 32;
  bool srgb8 = true;
};

constexpr double kPi = 3.14159265358979;

template <class S>
vec4<S> fetchLatLongTexel(const CosineDefines& d, const Texture2D& map, vec2<S> texel, S linear_scale) {
  return decodeCubeTexel(texture2D(map, (texel + S(0.5)) / vec2<S>(S(2.0 * d.latlong_rows), S(d.latlong_rows))),
                         linear_scale, d.srgb8);
}

template <class S>
vec4<S> cosinePrefilter(const CosineDefines& d, const TextureCube& input, double input_face_size, double input_scale,
                        double output_scale, int face_index, double output_face_size, vec2<S> v_face_st) {
  const S u_input_face_size = S(input_face_size);
  vec2<S> block = floor(v_face_st * S(output_face_size)) * S(double(d.prefilter_factor));
  vec4<S> sum(S(0.0));
  S weight_sum = S(0.0);
  for (int dy = 0; dy < d.prefilter_factor; ++dy)
    for (int dx = 0; dx < d.prefilter_factor; ++dx) {
      vec2<S> texel = block + vec2<S>(S(double(dx)), S(double(dy)));
      vec2<S> c = S(2.0) * (texel + S(0.5)) / u_input_face_size - S(1.0);
      S q = S(1.0) + dot(c, c);
      S weight = S(1.0) / (q * glsl::sqrt(q));
      vec4<S> t = fetchCubeTexel(input, S(double(face_index)), texel, u_input_face_size, S(input_scale), d.srgb8);
      sum += weight * vec4<S>(t.rgb() * t.w, t.w);
      weight_sum += weight;
    }
  vec4<S> mean = sum / weight_sum;
  return encodeCubeTexel(mean.rgb(), mean.w, S(output_scale), d.srgb8);
}

template <class S>
vec4<S> cosineEast(const CosineDefines& d, const TextureCube& input, double input_face_size, double input_scale,
                   double output_scale, vec2<S> v_face_st) {
  const S tap_step_rad = S(kPi / (2.0 * d.half_taps + 1.0));
  S theta = S(kPi) * v_face_st.y;
  S phi = S(2.0 * kPi) * v_face_st.x;
  vec3<S> dir{glsl::sin(theta) * glsl::cos(phi), glsl::sin(theta) * glsl::sin(phi), glsl::cos(theta)};
  vec3<S> east{-glsl::sin(phi), glsl::cos(phi), S(0.0)};
  vec4<S> sum(S(0.0));
  S weight_sum = S(0.0);
  for (int i = -d.half_taps; i <= d.half_taps; ++i) {
    S angle = S(double(i)) * tap_step_rad;
    S c = glsl::cos(angle);
    S weight = c * c;
    sum += weight * sampleCubeBilinear(input, c * dir + glsl::sin(angle) * east, S(input_face_size), S(input_scale),
                                       d.srgb8);
    weight_sum += weight;
  }
  vec4<S> mean = sum / weight_sum;
  return encodeCubeTexel(mean.rgb(), mean.w, S(output_scale), d.srgb8);
}

template <class S>
vec4<S> cosineNorth(const CosineDefines& d, const Texture2D& latlong, double input_scale, double output_scale,
                    vec2<S> v_face_st) {
  const S rows = S(double(d.latlong_rows)), columns = S(2.0 * d.latlong_rows);
  vec2<S> texel = floor(v_face_st * vec2<S>(columns, rows));
  vec4<S> sum(S(0.0));
  S weight_sum = S(0.0);
  for (int j = -d.latlong_rows / 2; j <= d.latlong_rows / 2; ++j) {
    S row = texel.y + S(double(j));
    S column = texel.x;
    if (row < S(0.0) || row > rows - S(0.5)) {
      row = row < S(0.0) ? -row - S(1.0) : S(2.0) * rows - row - S(1.0);
      column = glsl::mod(column + rows, columns);
    }
    S weight = glsl::cos(S(double(j)) * S(kPi / d.latlong_rows));
    sum += weight * fetchLatLongTexel(d, latlong, vec2<S>(column, row), S(input_scale));
    weight_sum += weight;
  }
  vec4<S> mean = sum / weight_sum;
  return encodeCubeTexel(mean.rgb(), mean.w, S(output_scale), d.srgb8);
}

template <class S>
vec4<S> sampleLatLongBilinear(const CosineDefines& d, const Texture2D& map, S theta, S phi, S linear_scale) {
  S rows = S(double(d.latlong_rows)), columns = S(2.0 * d.latlong_rows);
  vec2<S> uv{phi / S(2.0 * kPi) * columns - S(0.5), glsl::clamp(theta / S(kPi) * rows - S(0.5), S(0.0), rows - S(1.0))};
  vec2<S> base = floor(uv);
  vec2<S> f = uv - base;
  S x0 = glsl::mod(base.x, columns);
  S x1 = glsl::mod(base.x + S(1.0), columns);
  S y1 = glsl::min(base.y + S(1.0), rows - S(1.0));
  vec4<S> top = mix(fetchLatLongTexel(d, map, {x0, base.y}, linear_scale),
                    fetchLatLongTexel(d, map, {x1, base.y}, linear_scale), f.x);
  vec4<S> bottom =
      mix(fetchLatLongTexel(d, map, {x0, y1}, linear_scale), fetchLatLongTexel(d, map, {x1, y1}, linear_scale), f.x);
  return mix(top, bottom, f.y);
}

// The resampling pass with u_new_weight 1 (no blend with a previous map).
template <class S>
vec4<S> cosineResample(const CosineDefines& d, const Texture2D& latlong, double input_scale, double output_scale,
                       const FaceAxes& axes, vec2<S> v_face_st) {
  vec3<S> n = texelDirection(axes, v_face_st);
  vec4<S> sum = sampleLatLongBilinear(d, latlong, glsl::atan(length(n.xy()), n.z), glsl::atan(n.y, n.x), S(input_scale));
  vec4<S> fresh = sum.w > S(1e-6) ? vec4<S>(sum.rgb() / sum.w, sum.w) : vec4<S>(S(0.0), S(0.0), S(0.0), glsl::max(sum.w, S(0.0)));
  return encodeCubeTexel(fresh.rgb(), fresh.w, S(output_scale), d.srgb8);
}

// ---- glossy_lobe.frag -------------------------------------------------------

struct GlossyUniforms {
  int half_taps = 8;
  bool srgb8 = true;
  double tap_step_rad, east_power, north_power;
  double input_face_size, input_scale, output_scale;
  // NORTH_PASS only: the prefiltered map, for the taps near the poles.
  double prefiltered_face_size, prefiltered_scale, pole_cosine;
};

template <class S> vec3<S> eastTangent(vec3<S> n) {
  vec3<S> across_meridian{-n.y, n.x, S(0.0)};
  return length(across_meridian) < S(1e-4) ? vec3<S>(S(1.0), S(0.0), S(0.0)) : normalize(across_meridian);
}

template <class S> S lobeWeight(S power, S a) {
  S a2 = a * a;
  S s = a2 * (S(0.5) + a2 * (S(1.0 / 12.0) + a2 * (S(1.0 / 45.0) + a2 * (S(17.0 / 2520.0) + a2 * S(31.0 / 14175.0)))));
  return glsl::exp(-power * s);
}

template <class S>
vec4<S> eastIntegral(const GlossyUniforms& u, const TextureCube& map, S face_size, S scale, vec3<S> d, vec3<S> t) {
  vec4<S> sum(S(0.0));
  S weight_sum = S(0.0);
  for (int i = -u.half_taps; i <= u.half_taps; ++i) {
    S a = S(double(i)) * S(u.tap_step_rad);
    S w = lobeWeight(S(u.east_power), a);
    sum += w * sampleCubeBilinear(map, glsl::cos(a) * d + glsl::sin(a) * t, face_size, scale, u.srgb8);
    weight_sum += w;
  }
  return sum / weight_sum;
}

template <class S>
vec4<S> glossyEast(const GlossyUniforms& u, const TextureCube& input, const FaceAxes& axes, vec2<S> v_face_st) {
  vec3<S> n = texelDirection(axes, v_face_st);
  vec4<S> mean = eastIntegral(u, input, S(u.input_face_size), S(u.input_scale), n, eastTangent(n));
  return encodeCubeTexel(mean.rgb(), mean.w, S(u.output_scale), u.srgb8);
}

template <class S>
vec4<S> glossyNorth(const GlossyUniforms& u, const TextureCube& input, const TextureCube& prefiltered,
                    const FaceAxes& axes, vec2<S> v_face_st) {
  vec3<S> r = texelDirection(axes, v_face_st);
  vec3<S> east = eastTangent(r);
  vec3<S> north = cross(r, east);
  vec4<S> sum(S(0.0));
  S weight_sum = S(0.0);
  for (int j = -u.half_taps; j <= u.half_taps; ++j) {
    S b = S(double(j)) * S(u.tap_step_rad);
    vec3<S> d = glsl::cos(b) * r + glsl::sin(b) * north;
    vec4<S> inner = glsl::abs(d.z) > S(u.pole_cosine)
                        ? eastIntegral(u, prefiltered, S(u.prefiltered_face_size), S(u.prefiltered_scale), d, east)
                        : sampleCubeBilinear(input, d, S(u.input_face_size), S(u.input_scale), u.srgb8);
    S w = lobeWeight(S(u.north_power), b);
    sum += w * inner;
    weight_sum += w;
  }
  sum /= weight_sum;
  vec4<S> fresh = sum.w > S(1e-6) ? vec4<S>(sum.rgb() / sum.w, sum.w) : vec4<S>(S(0.0), S(0.0), S(0.0), glsl::max(sum.w, S(0.0)));
  return encodeCubeTexel(fresh.rgb(), fresh.w, S(u.output_scale), u.srgb8);
}

// ---- sh9_irradiance.frag (u_new_weight 1: no blend) ------------------------

template <class S>
vec4<S> sh9Irradiance(const std::array<glm::dvec3, 9>& polynomial, double output_scale, bool srgb8,
                      const FaceAxes& axes, vec2<S> v_face_st) {
  std::array<vec3<S>, 9> p;
  for (int k = 0; k < 9; ++k) p[static_cast<size_t>(k)] = toS<S>(polynomial[static_cast<size_t>(k)]);
  vec3<S> n = texelDirection(axes, v_face_st);
  vec3<S> e = p[0] + p[1] * n.x + p[2] * n.y + p[3] * n.z + p[4] * (n.x * n.y) + p[5] * (n.y * n.z) +
              p[6] * (n.x * n.z) + p[7] * (n.z * n.z) + p[8] * (n.x * n.x - n.y * n.y);
  vec4<S> blended{max(e, vec3<S>(S(0.0))), S(1.0)};
  return encodeCubeTexel(blended.rgb(), blended.w, S(output_scale), srgb8);
}

// ---- sphere_object.frag (REFLECTION_LOWER_RUNG 0: the mirror map) -----------

struct SphereUniforms {
  glm::dvec3 albedo{0.8};
  double material_ambient = 0.0, k_diffuse = 1.0, k_specular = 0.0, shininess = 32.0, k_reflect = 0.0;
  glm::dvec3 ambient_rgb{0.0}, highlight_direction_w{0.0, 0.0, 1.0}, highlight_rgb{0.0};
  std::array<glm::dvec3, 4> clipped_direction_w{}, clipped_diffuse_rgb{};
  double diffuse_face_size = 16, diffuse_scale = 1, reflection_face_size = 64, reflection_scale = 1;
  bool srgb8 = true;
};

template <class S>
vec4<S> sphereObject(const SphereUniforms& u, const TextureCube& diffuse_map, const TextureCube& reflection_map,
                     vec3<S> v_normal_w, vec3<S> v_to_eye_w) {
  vec3<S> n = normalize(v_normal_w);
  vec3<S> to_eye = normalize(v_to_eye_w);
  vec3<S> half_vector = normalize(toS<S>(u.highlight_direction_w) + to_eye);
  vec3<S> n_minus_h = n - half_vector;
  S x = S(0.5) * dot(n_minus_h, n_minus_h);
  S ln_n_dot_h = -x * (S(1.0) + x * (S(0.5) + x * (S(1.0 / 3.0) + x * (S(0.25) + x * (S(0.2) + x * S(1.0 / 6.0))))));
  S n_dot_h = S(1.0) - x;
  S highlight = x < S(0.25) ? glsl::exp(S(u.shininess) * ln_n_dot_h)
                            : (n_dot_h > S(0.0) ? glsl::pow(n_dot_h, S(u.shininess)) : S(0.0));
  vec3<S> mirror = reflect(-to_eye, n);
  vec3<S> diffuse = sampleCubeBilinear(diffuse_map, n, S(u.diffuse_face_size), S(u.diffuse_scale), u.srgb8).rgb();
  for (int k = 0; k < 4; ++k)
    diffuse += toS<S>(u.clipped_diffuse_rgb[static_cast<size_t>(k)]) *
               glsl::max(dot(n, toS<S>(u.clipped_direction_w[static_cast<size_t>(k)])), S(0.0));
  vec3<S> reflection =
      sampleCubeBilinear(reflection_map, mirror, S(u.reflection_face_size), S(u.reflection_scale), u.srgb8).rgb();
  vec3<S> color = toS<S>(u.ambient_rgb) * S(u.material_ambient) + S(u.k_diffuse) * diffuse * toS<S>(u.albedo) +
                  S(u.k_specular) * toS<S>(u.highlight_rgb) * highlight + S(u.k_reflect) * reflection;
  return {linearToSrgb(color), S(1.0)};
}

// ---- depth_packing.glsl -----------------------------------------------------

template <class S> vec4<S> packDepth(S depth01) {
  S high_and_fraction = glsl::clamp(depth01, S(0.0), S(1.0)) * S(65535.0 / 256.0);
  S high = glsl::min(glsl::floor(high_and_fraction), S(255.0));
  S low = glsl::min(glsl::floor((high_and_fraction - high) * S(256.0) + S(0.5)), S(255.0));
  return {high / S(255.0), low / S(255.0), S(0.0), S(1.0)};
}

template <class S> S unpackDepth(vec4<S> stored_texel) {
  return (glsl::floor(stored_texel.x * S(255.0) + S(0.5)) + glsl::floor(stored_texel.y * S(255.0) + S(0.5)) / S(256.0)) *
         S(256.0 / 65535.0);
}

// ---- ground_composite.frag --------------------------------------------------

// camera_uv from the fragment's window position; the camera sRGB.
template <class S>
vec4<S> groundComposite(const Texture2D& camera, const Texture2D& fraction, glm::dvec2 image_size_px,
                        vec2<S> gl_frag_coord, vec2<S> v_region_uv) {
  const vec2<S> u_image_size_px = toS<S>(image_size_px);
  vec2<S> camera_uv{gl_frag_coord.x / u_image_size_px.x, S(1.0) - gl_frag_coord.y / u_image_size_px.y};
  vec3<S> camera_linear = srgbToLinear(texture2D(camera, camera_uv).rgb());
  vec3<S> f = texture2D(fraction, v_region_uv).rgb();
  return {linearToSrgb(camera_linear * f), S(1.0)};
}

// ---- camera_yuv_planes.frag (I420) -------------------------------------------

template <class S> vec4<S> yuvPlanes(const float (&matrix)[9], const float (&offset)[3], vec3<S> code) {
  const vec3<S> columns[3] = {{S(matrix[0]), S(matrix[1]), S(matrix[2])},
                              {S(matrix[3]), S(matrix[4]), S(matrix[5])},
                              {S(matrix[6]), S(matrix[7]), S(matrix[8])}};
  return {clamp(glsl::mul(columns, code) + vec3<S>(S(offset[0]), S(offset[1]), S(offset[2])), S(0.0), S(1.0)), S(1.0)};
}

// ---- ground_shadow.frag -----------------------------------------------------

struct GroundShadowUniforms {
  glm::dvec3 share{0.0};
  double tan_cone = 0.0;
  glm::dvec2 ground_gradient{0.0};
  double map_width_m = 0.0, depth_range_m = 0.0, texel_uv = 0.0, bias01 = 0.0;
  std::vector<glm::dvec2> taps;
  bool packed_depth = true;  // SHADOW_DEPTH_PACKED
};

template <class S> S storedDepth(const GroundShadowUniforms& u, const Texture2D& shadow_map, vec2<S> uv) {
  if (u.packed_depth) return unpackDepth(texture2D(shadow_map, uv));
  return texture2D(shadow_map, uv).x;
}

template <class S>
vec4<S> groundShadow(const GroundShadowUniforms& u, const Texture2D& shadow_map, vec3<S> v_light_clip) {
  const S k_empty01 = S(0.01);
  const vec2<S> u_ground_gradient = toS<S>(u.ground_gradient);
  vec3<S> clip = v_light_clip;
  vec2<S> uv = S(0.5) * clip.xy() + S(0.5);
  S receiver = S(0.5) * clip.z + S(0.5);
  S metres_to_uv = S(u.tan_cone) / S(u.map_width_m);
  S search_uv = receiver * S(u.depth_range_m) * metres_to_uv + S(u.texel_uv);
  S bias = S(u.bias01) + S(0.71) * S(u.texel_uv) * length(u_ground_gradient);
  S blocker_sum = S(0.0);
  S blockers = S(0.0);
  for (const glm::dvec2& tap : u.taps) {
    vec2<S> offset = search_uv * toS<S>(tap);
    S d = storedDepth(u, shadow_map, uv + offset);
    if (d > k_empty01 && d < receiver + dot(u_ground_gradient, offset) + bias) {
      blocker_sum += d;
      blockers += S(1.0);
    }
  }
  S hidden = S(0.0);
  if (blockers > S(0.5)) {
    S distance_m = (receiver - blocker_sum / blockers) * S(u.depth_range_m);
    S filter_uv = glsl::max(distance_m, S(0.0)) * metres_to_uv + S(u.texel_uv);
    for (const glm::dvec2& tap : u.taps) {
      vec2<S> offset = filter_uv * toS<S>(tap);
      S d = storedDepth(u, shadow_map, uv + offset);
      hidden += d > k_empty01 && d < receiver + dot(u_ground_gradient, offset) + bias ? S(1.0) : S(0.0);
    }
  }
  return {toS<S>(u.share) * (hidden / S(double(u.taps.size()))), S(0.0)};
}

}  // namespace probelight::twin
