// The CPU reference of EnvironmentMaps::updateDiffuse
// (ibl::irradianceOverPiByCosinePasses) and a bound, per texel, on how far
// the GPU may be from it, derived from the storage and the shader's floats.
//
// The GPU computes P = L(R V) and A = L(V) (premultiplied radiance and
// coverage; L = prefilter, east cos^2 into a latitude-longitude map, north
// cos on it, bilinear resampling to the cube: all weighted means with
// non-negative weights, so |L(e)| <= L(|e|)), then
// rgb = P / A. With errors eP, eA on P and A, |rgb - P / A| <= (eP + F eA) / A
// (first order; F = P / A). eP and eA collect, each pushed through the part
// of L that follows the point where it enters (the CPU functions are those
// same linear operators, so they propagate the bounds exactly):
//  - the reflection map's own storage (only when the reference is given the
//    map before upload; none when it is given the map read back);
//  - the prefiltered map's storage (RGBA8: rounding 0.5 level + the shader's
//    approximate pow in encode and decode, 0.1 level each, llvmpipe's fetch
//    returning some bytes up to ~0.15 level low: 0.7 level for rgb at the
//    reflection's scale, 0.75 / 255 for alpha; half floats: 2^-11 relative),
//    through the rest of L: L' = L without its prefilter, computed as L of
//    the map upsampled by constant blocks;
//  - the prefilter's weights: the shader weights a texel by the solid-angle
//    density at its centre, (1 + u^2 + v^2)^-1.5, not by
//    ibl::cubeTexelSolidAngle; with delta the largest relative difference of
//    the two normalised weights in any block (computed below: ~1e-4), the
//    block mean moves by <= delta * (max - min of the block);
//  - the east latitude-longitude map's storage (as the prefiltered map's),
//    through the north pass and the resampling (the north taps fetch texel
//    centres: no direction error there);
//  - the north map's storage, through the resampling;
//  - fp32 directions: ~1e-5 rad of error, direction_error_rad (single precision through
//    normalize, cross, atan and the tap rotation, and llvmpipe's polynomial
//    sin/cos) moves a bilinear sample of the prefiltered cube by
//    <= 1e-5 * face_size texels, and the resampling's lookup in the north
//    map by <= 1e-5 * columns / (2 pi sin theta) texels (azimuth is
//    ill-conditioned near the poles; theta >= that of the cube texel centre
//    nearest a pole), which changes each by at most that times the spread of
//    the 3x3 texels around each corner of its cell (the "dilated spread"
//    maps below);
//  - fp32 sums of up to 2 x 33 terms and the division: 40 u of the value,
//    u the fragment shader's unit roundoff.
// The output's own storage rounding is left to the caller (it depends on the
// output scale, which blending changes).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "gles_test_support.hpp"
#include "ibl/spherical_blur.hpp"
#include "passes/environment_maps.hpp"

namespace probelight::test {

struct CosineReference {
  ibl::CubeMapRGB rgb;              // ibl::irradianceOverPiByCosinePasses
  std::vector<float> alpha;         // coverage L(V), layout as CubeMapRGB::faces
  ibl::CubeMapRGB tolerance;        // bound on |GPU rgb - rgb| before the output's storage rounding
  std::vector<float> alpha_tolerance;
};

// Rounding of a stored linear value: RGBA8 by `levels` 8-bit levels of the
// sRGB code at `scale`; half floats 2^-11 relative.
inline double storageRoundingBound(passes::CubeStorage storage, double value, double scale, double levels) {
  if (storage == passes::CubeStorage::kLinearHalfFloat) return std::abs(value) * std::ldexp(1.0, -11);
  const double encoded = ibl::linearToSrgb(std::max(0.0, value) / scale);
  return scale * srgbDecodeSlope(std::min(1.0, encoded + levels / 255.0)) * levels / 255.0;
}

namespace detail {

inline ibl::CubeMapRGB mapTexels(const ibl::CubeMapRGB& in, const std::function<glm::vec3(int, int, int)>& f) {
  ibl::CubeMapRGB out(in.face_size);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < in.face_size; ++y)
      for (int x = 0; x < in.face_size; ++x) out.texel(face, x, y) = f(face, x, y);
  return out;
}

// Each texel repeated over a factor x factor block.
inline ibl::CubeMapRGB upsample(const ibl::CubeMapRGB& in, int factor) {
  ibl::CubeMapRGB out(in.face_size * factor);
  return mapTexels(out, [&](int face, int x, int y) { return in.texel(face, x / factor, y / factor); });
}

// Max - min per channel over the texels of `in` within [x0, x1] x [y0, y1] (clamped to the face).
inline glm::vec3 spread(const ibl::CubeMapRGB& in, int face, int x0, int y0, int x1, int y1) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (int y = std::max(0, y0); y <= std::min(in.face_size - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(in.face_size - 1, x1); ++x) {
      lo = glm::min(lo, in.texel(face, x, y));
      hi = glm::max(hi, in.texel(face, x, y));
    }
  return hi - lo;
}

// Spread of the 3x3 texels around each texel: >= the spread of every
// bilinear cell that has the texel as a corner.
inline ibl::CubeMapRGB dilatedSpread(const ibl::CubeMapRGB& in) {
  return mapTexels(in, [&](int face, int x, int y) { return spread(in, face, x - 1, y - 1, x + 1, y + 1); });
}

// Largest relative difference between the shader's normalised prefilter
// weights (density at the texel centre) and the exact normalised solid angles.
inline double prefilterWeightDelta(int input_face_size, int factor) {
  double delta = 0.0;
  for (int by = 0; by < input_face_size; by += factor) {
    for (int bx = 0; bx < input_face_size; bx += factor) {
      double exact_sum = 0.0, density_sum = 0.0;
      std::vector<double> exact, density;
      for (int y = by; y < by + factor; ++y) {
        for (int x = bx; x < bx + factor; ++x) {
          const double u = 2.0 * (x + 0.5) / input_face_size - 1.0, v = 2.0 * (y + 0.5) / input_face_size - 1.0;
          exact.push_back(ibl::cubeTexelSolidAngle(x, y, input_face_size));
          density.push_back(std::pow(1.0 + u * u + v * v, -1.5));
          exact_sum += exact.back();
          density_sum += density.back();
        }
      }
      for (size_t i = 0; i < exact.size(); ++i)
        delta = std::max(delta, std::abs((density[i] / density_sum) / (exact[i] / exact_sum) - 1.0));
    }
  }
  return delta;
}

}  // namespace detail

// `radiance` and `validity` as given to setReflection (input_levels: the
// 8-bit levels of their upload rounding, 0.5; or 0 when they are the map read
// back, i.e. exactly what the GPU holds). `scale`: the reflection map's
// linear_scale. `unit_roundoff`: the fragment shader's.
inline CosineReference cosineIrradianceReference(const ibl::CubeMapRGB& radiance, const std::vector<float>& validity,
                                                 const passes::EnvironmentMapSettings& settings,
                                                 passes::CubeStorage storage, double scale, double input_levels,
                                                 double unit_roundoff, double direction_error_rad = 1e-5) {
  using detail::mapTexels;
  const ibl::CosineIrradianceSettings cosine = passes::cosineIrradianceSettings(settings);
  const int factor = radiance.face_size / settings.prefilter_face_size;
  const size_t r2 = static_cast<size_t>(radiance.face_size) * radiance.face_size;
  const ibl::CubeMapRGB valid = mapTexels(radiance, [&](int face, int x, int y) {
    return glm::vec3(validity[face * r2 + static_cast<size_t>(y) * radiance.face_size + x]);
  });
  const ibl::CubeMapRGB premultiplied =
      mapTexels(radiance, [&](int face, int x, int y) { return radiance.texel(face, x, y) * valid.texel(face, x, y); });

  CosineReference ref;
  ref.rgb = ibl::irradianceOverPiByCosinePasses(radiance, cosine, &validity);
  const ibl::CubeMapRGB coverage = ibl::irradianceOverPiByCosinePasses(valid, cosine);  // L(V) / L(1), L(1) = 1

  // L' (everything after the prefilter, on a prefiltered-size map), and the
  // parts after the east and the north latitude-longitude maps.
  const auto after_prefilter = [&](const ibl::CubeMapRGB& m) {
    return ibl::irradianceOverPiByCosinePasses(detail::upsample(m, factor), cosine);
  };
  const auto after_east = [&](const ibl::LatLongRGB& m) {
    return ibl::latLongToCube(ibl::northPassOnLatLong(m), cosine.output_face_size);
  };
  const auto after_north = [&](const ibl::LatLongRGB& m) { return ibl::latLongToCube(m, cosine.output_face_size); };

  const double delta = detail::prefilterWeightDelta(radiance.face_size, factor);
  const double rgb_levels = 0.7, alpha_levels = 0.75;
  const double alpha_rounding = storage == passes::CubeStorage::kSrgb8 ? alpha_levels / 255.0 : std::ldexp(1.0, -11);

  const ibl::CubeMapRGB pre_p = ibl::downsampleCubeMap(premultiplied, factor);
  const ibl::CubeMapRGB pre_a = ibl::downsampleCubeMap(valid, factor);
  const ibl::LatLongRGB east_p = ibl::eastPassToLatLong(pre_p, cosine.intermediate_rows, cosine.half_taps);
  const ibl::LatLongRGB east_a = ibl::eastPassToLatLong(pre_a, cosine.intermediate_rows, cosine.half_taps);
  const ibl::LatLongRGB north_p = ibl::northPassOnLatLong(east_p);
  const ibl::LatLongRGB north_a = ibl::northPassOnLatLong(east_a);

  // Errors entering at the prefiltered map (storage, weights, fp32 taps on it).
  const auto pre_error = [&](const ibl::CubeMapRGB& pre, const ibl::CubeMapRGB& source, bool alpha) {
    const ibl::CubeMapRGB dilated = detail::dilatedSpread(pre);
    const double sample_shift_texels = direction_error_rad * pre.face_size;
    return mapTexels(pre, [&](int face, int x, int y) {
      const glm::vec3 block = detail::spread(source, face, x * factor, y * factor, x * factor + factor - 1,
                                             y * factor + factor - 1);
      glm::vec3 e = static_cast<float>(delta) * block + static_cast<float>(sample_shift_texels) * dilated.texel(face, x, y);
      for (int c = 0; c < 3; ++c)
        e[c] += static_cast<float>(alpha ? alpha_rounding : storageRoundingBound(storage, pre.texel(face, x, y)[c], scale, rgb_levels));
      return e;
    });
  };
  // Errors entering at a latitude-longitude map: its storage, and (for the
  // north map, which the resampling looks up bilinearly) the lookup's shift.
  double min_sin_theta = 1.0;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < cosine.output_face_size; ++y)
      for (int x = 0; x < cosine.output_face_size; ++x)
        min_sin_theta = std::min(min_sin_theta, std::sin(ibl::colatitudeRad(ibl::cubeTexelCenterDirection(
                                                    face, x, y, cosine.output_face_size))));
  const auto latlong_error = [&](const ibl::LatLongRGB& map, bool alpha, double sample_shift_texels) {
    ibl::LatLongRGB e(map.width, map.height);
    for (int y = 0; y < map.height; ++y) {
      for (int x = 0; x < map.width; ++x) {
        glm::vec3 lo(1e30f), hi(-1e30f);
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const glm::vec3& t = map.texel((x + dx + map.width) % map.width, std::clamp(y + dy, 0, map.height - 1));
            lo = glm::min(lo, t);
            hi = glm::max(hi, t);
          }
        glm::vec3 bound = static_cast<float>(sample_shift_texels) * (hi - lo);
        for (int c = 0; c < 3; ++c)
          bound[c] += static_cast<float>(alpha ? alpha_rounding
                                               : storageRoundingBound(storage, map.texel(x, y)[c], scale, rgb_levels));
        e.texel(x, y) = bound;
      }
    }
    return e;
  };
  const double north_shift_texels =
      direction_error_rad * std::max(cosine.intermediate_rows / M_PI, 2.0 * cosine.intermediate_rows /
                                                                          (2.0 * M_PI * min_sin_theta));
  ibl::CubeMapRGB e_p2 = after_east(latlong_error(east_p, false, 0.0));
  ibl::CubeMapRGB e_a2 = after_east(latlong_error(east_a, true, 0.0));
  const ibl::CubeMapRGB e_p3 = after_north(latlong_error(north_p, false, north_shift_texels));
  const ibl::CubeMapRGB e_a3 = after_north(latlong_error(north_a, true, north_shift_texels));
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (size_t i = 0; i < e_p2.faces[face].size(); ++i) {
      e_p2.faces[face][i] += e_p3.faces[face][i];
      e_a2.faces[face][i] += e_a3.faces[face][i];
    }
  const ibl::CubeMapRGB e_p1 = after_prefilter(pre_error(pre_p, premultiplied, false));
  const ibl::CubeMapRGB e_a1 = after_prefilter(pre_error(pre_a, valid, true));
  ibl::CubeMapRGB e_in(cosine.output_face_size);
  if (input_levels > 0.0) {
    const ibl::CubeMapRGB rounding = mapTexels(radiance, [&](int face, int x, int y) {
      glm::vec3 e;
      for (int c = 0; c < 3; ++c) e[c] = static_cast<float>(storageRoundingBound(storage, radiance.texel(face, x, y)[c], scale, input_levels));
      return e;
    });
    e_in = ibl::irradianceOverPiByCosinePasses(rounding, cosine, &validity);  // = L(Q V) / A
  }

  const int n = cosine.output_face_size;
  ref.tolerance = ibl::CubeMapRGB(n);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const double a = coverage.texel(face, x, y).r;
        const double e_a = e_a1.texel(face, x, y).r + e_a2.texel(face, x, y).r;
        ref.alpha.push_back(static_cast<float>(a));
        ref.alpha_tolerance.push_back(static_cast<float>(e_a + 4.0 * unit_roundoff));
        for (int c = 0; c < 3; ++c) {
          const double f = ref.rgb.texel(face, x, y)[c];
          const double e_p = e_p1.texel(face, x, y)[c] + e_p2.texel(face, x, y)[c];
          ref.tolerance.texel(face, x, y)[c] = static_cast<float>(
              a > 1e-3 ? (e_p + f * e_a) / (a - e_a) + e_in.texel(face, x, y)[c] + 40.0 * unit_roundoff * f
                       : 1e30);  // nothing seen: only the 0 branch is checked (by the caller)
        }
      }
    }
  }
  return ref;
}

}  // namespace probelight::test
