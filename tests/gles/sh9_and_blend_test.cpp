// The SH9 diffuse map on the GPU (EnvironmentMaps::updateDiffuseFromSH9)
// against ibl::sh9DiffuseMap, and temporal blending of the diffuse map (both
// ways of making it) against previous + w (new - previous), for both cube
// storages. Also times the SH9 chain (read-back + CPU projection + render)
// next to the blur on this machine.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <optional>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "cosine_irradiance_reference.hpp"
#include "gles_test_support.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/spherical_blur.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "passes/environment_maps.hpp"

namespace probelight {
namespace {

using test::GpuTest;

const glm::dvec3 kLamp = glm::normalize(glm::dvec3(-0.5, 0.45, 0.74));
const glm::dvec3 kBlindSpot = glm::normalize(glm::dvec3(0.2, -0.9, -0.4));

// The analytic room plus a lamp (3x the sky), times `gain`. With
// `validity`, a 0.4-rad blind spot (rgb 0, validity 0) as the ball has.
ibl::CubeMapRGB roomWithLamp(int face_size, double gain, std::vector<float>* validity = nullptr) {
  ibl::CubeMapRGB cube(face_size);
  if (validity != nullptr) validity->assign(static_cast<size_t>(ibl::kCubeFaceCount) * face_size * face_size, 1.0f);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x) {
        const glm::dvec3 d = ibl::cubeTexelCenterDirection(face, x, y, face_size);
        glm::dvec3 value = test::analyticEnvironment(d);
        if (glm::dot(d, kLamp) > std::cos(0.25)) value += glm::dvec3(3.0, 2.6, 2.0);
        if (validity != nullptr && glm::dot(d, kBlindSpot) > std::cos(0.4)) {
          value = glm::dvec3(0.0);
          (*validity)[static_cast<size_t>(face) * face_size * face_size + static_cast<size_t>(y) * face_size + x] = 0.0f;
        }
        cube.texel(face, x, y) = glm::vec3(value * gain);
      }
    }
  }
  return cube;
}

// Unit roundoff of the fragment shader's floats on this GPU: the shaders get
// highp where the GPU has it in fragment shaders, mediump otherwise (the
// prelude in gl_objects.cpp decides by GL_FRAGMENT_PRECISION_HIGH, whatever
// Capabilities a test passes), so this is read from the real probe.
double fragmentUnitRoundoff() {
  const gles::Capabilities& caps = test::sharedCapabilities();
  const int bits = caps.fragment_highp ? caps.fragment_highp_mantissa_bits : caps.fragment_mediump_mantissa_bits;
  return std::ldexp(1.0, -(std::max(bits, 10) + 1));
}

// Storage rounding of one stored value `expected` (linear), in linear units:
//  - half floats keep 11 significant bits: |expected| * 2^-11;
//  - RGBA8 rounds the encoded value by up to 0.5 level; the shader's encode
//    (llvmpipe's approximate pow) adds up to 0.1 level (as measured for the
//    probe stage on a flat image, tests/gles/environment_maps_test.cpp):
//    0.6 level times the sRGB decode slope there, times the map's scale.
double storageTolerance(passes::CubeStorage storage, double expected, double linear_scale) {
  if (storage == passes::CubeStorage::kLinearHalfFloat) return std::abs(expected) * std::ldexp(1.0, -11);
  const double encoded = ibl::linearToSrgb(std::max(0.0, expected) / linear_scale);
  return linear_scale * test::srgbDecodeSlope(std::min(1.0, encoded + 0.6 / 255.0)) * 0.6 / 255.0;
}

// Alpha: exact for 1 in both storages; otherwise 0.5 / 255 (RGBA8) or 2^-11.
double alphaTolerance(passes::CubeStorage storage) {
  return storage == passes::CubeStorage::kSrgb8 ? 0.5 / 255.0 + 1e-6 : std::ldexp(1.0, -11);
}

// Bound on the shader's evaluation error of the SH9 polynomial, per channel:
// 14 u sum |p_k| (derived in tests/ibl/spherical_harmonics_test.cpp, where a
// mediump emulation checks it), u the fragment shader's unit roundoff.
glm::dvec3 sh9EvaluationTolerance(const ibl::SH9RGB& sh) {
  glm::dvec3 sum_abs(0.0);
  for (const glm::dvec3& p : ibl::sh9DiffusePolynomial(sh)) sum_abs += glm::abs(p);
  return 14.0 * fragmentUnitRoundoff() * sum_abs;
}

struct MapComparison {
  double max_error = 0.0;         // linear
  double max_excess = -1e9;       // error - tolerance; must stay <= 0
  double max_alpha_error = 0.0;
};

MapComparison compareMaps(const ibl::CubeMapRGB& gpu, const std::vector<float>& gpu_alpha,
                          const ibl::CubeMapRGB& expected, const std::vector<float>& expected_alpha,
                          passes::CubeStorage storage, double linear_scale, const glm::dvec3& arithmetic_tolerance) {
  MapComparison result;
  const int n = expected.face_size;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        for (int c = 0; c < 3; ++c) {
          const double want = expected.texel(face, x, y)[c];
          const double error = std::abs(gpu.texel(face, x, y)[c] - want);
          const double tolerance = storageTolerance(storage, want, linear_scale) + arithmetic_tolerance[c];
          result.max_error = std::max(result.max_error, error);
          result.max_excess = std::max(result.max_excess, error - tolerance);
        }
        const size_t i = static_cast<size_t>(face) * n * n + static_cast<size_t>(y) * n + x;
        result.max_alpha_error = std::max(result.max_alpha_error, std::abs(static_cast<double>(gpu_alpha[i]) - expected_alpha[i]));
      }
    }
  }
  return result;
}

double medianMs(std::vector<double> times) {
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

class Sh9DiffuseTest : public GpuTest, public ::testing::WithParamInterface<bool> {
 protected:
  // Maps for the storage under test; nullopt (test skipped) when native half floats are missing.
  std::optional<passes::EnvironmentMaps> makeMaps() {
    const bool force_8bit = GetParam();
    const gles::Capabilities caps =
        force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
    std::string error;
    std::optional<passes::EnvironmentMaps> maps(std::in_place);
    EXPECT_TRUE(maps->init(caps, {}, error)) << error;
    if (!force_8bit && maps->storage() != passes::CubeStorage::kLinearHalfFloat) return std::nullopt;
    return maps;
  }
};

// GPU vs ibl::sh9DiffuseMap of the same coefficients. Tolerance per value:
// the storage's rounding (storageTolerance) plus the shader's evaluation
// error (sh9EvaluationTolerance; ~1e-6 in fp32, the 8-bit step is ~1e-3).
// The SH9 chain (read-back, projection on the CPU, render) is timed with
// the blur beside it.
TEST_P(Sh9DiffuseTest, MatchesCpuReferenceAndIsTimed) {
  auto maps = makeMaps();
  if (!maps) GTEST_SKIP() << "this GPU cannot render half floats";
  std::string error;
  std::vector<float> reflection_validity;
  // 2.5x the room, so the SH9 map's largest value (0.57 at 1x) exceeds 1 and
  // the 8-bit path has to use a scale above 1.
  constexpr double kGain = 2.5;
  const ibl::CubeMapRGB room = roomWithLamp(maps->settings().reflection_face_size, kGain, &reflection_validity);
  ASSERT_TRUE(maps->setReflection(room, error, &reflection_validity)) << error;

  std::vector<double> readback_ms;
  std::vector<double> project_ms;
  std::vector<double> render_ms;
  std::vector<double> blur_ms;
  ibl::SH9RGB sh;
  std::vector<float> validity;
  for (int run = 0; run < 7; ++run) {
    glFinish();
    const auto t0 = std::chrono::steady_clock::now();
    const auto reflection = maps->readReflection(error, &validity);
    ASSERT_TRUE(reflection) << error;
    const auto t1 = std::chrono::steady_clock::now();
    sh = ibl::projectToSH9(*reflection, &validity);
    const auto t2 = std::chrono::steady_clock::now();
    ASSERT_TRUE(maps->updateDiffuseFromSH9(sh, error)) << error;
    glFinish();
    const auto t3 = std::chrono::steady_clock::now();
    ASSERT_TRUE(maps->updateDiffuse(error)) << error;
    glFinish();
    const auto t4 = std::chrono::steady_clock::now();
    readback_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    project_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    render_ms.push_back(std::chrono::duration<double, std::milli>(t3 - t2).count());
    blur_ms.push_back(std::chrono::duration<double, std::milli>(t4 - t3).count());
  }
  // The last update was the blur; render the SH9 map once more to compare it.
  ASSERT_TRUE(maps->updateDiffuseFromSH9(sh, error)) << error;
  std::vector<float> alpha;
  const auto gpu = maps->readDiffuse(error, &alpha);
  ASSERT_TRUE(gpu) << error;
  ASSERT_TRUE(test::allFinite(*gpu));

  const ibl::CubeMapRGB cpu = ibl::sh9DiffuseMap(sh, maps->settings().diffuse_face_size);
  const std::vector<float> ones(alpha.size(), 1.0f);
  const double scale = maps->diffuse().linear_scale;
  const MapComparison result = compareMaps(*gpu, alpha, cpu, ones, maps->storage(), scale, sh9EvaluationTolerance(sh));
  std::printf("[ measure  ] SH9 diffuse %s (scale %.2f): max |GPU-CPU| %.2e, alpha %.1e; median ms: read-back %.2f + "
              "projection %.2f + render %.2f = %.2f; cosine passes (3) %.2f\n",
              maps->storageDescription().c_str(), scale, result.max_error, result.max_alpha_error,
              medianMs(readback_ms), medianMs(project_ms), medianMs(render_ms),
              medianMs(readback_ms) + medianMs(project_ms) + medianMs(render_ms), medianMs(blur_ms));
  EXPECT_LE(result.max_excess, 0.0);
  EXPECT_EQ(result.max_alpha_error, 0.0);  // alpha 1 is exact in both storages
  if (maps->storage() == passes::CubeStorage::kSrgb8) {
    // The scale is the largest stored value: the lamp side exceeds 1 and
    // must not clip.
    float largest = 0.0f;
    for (const auto& face : cpu.faces) {
      for (const glm::vec3& t : face) largest = std::max({largest, t.r, t.g, t.b});
    }
    EXPECT_GT(largest, 1.0f);
    EXPECT_NEAR(scale, largest, 1e-5 * largest);
  }
  // The fit ignored the blind spot (rgb 0 there): facing it, the SH9 map is
  // within 3% of the brute-force irradiance of the room without a hole
  // (what SH9 achieves on this room, tests/ibl), not darkened.
  const ibl::CubeMapRGB full_room = roomWithLamp(maps->settings().reflection_face_size, kGain);
  const double truth = ibl::irradianceFromCubeMap(full_room, kBlindSpot).r;
  EXPECT_NEAR(M_PI * gpu->sampleNearest(kBlindSpot).r, truth, 0.03 * truth);
}

INSTANTIATE_TEST_SUITE_P(Storage, Sh9DiffuseTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("Forced8Bit") : std::string("Native");
                         });

// ---- Temporal blending ----------------------------------------------------

struct DiffuseState {
  ibl::CubeMapRGB rgb;
  std::vector<float> alpha;
  double scale = 1.0;
};

std::optional<DiffuseState> readDiffuseState(const passes::EnvironmentMaps& maps, std::string& error) {
  DiffuseState state;
  auto rgb = maps.readDiffuse(error, &state.alpha);
  if (!rgb) return std::nullopt;
  state.rgb = std::move(*rgb);
  state.scale = maps.diffuse().linear_scale;
  return state;
}

// What an update with weight 1 would store, computed on the CPU from exactly
// what the GPU used, and the shader's arithmetic error on it (per channel,
// and for alpha).
struct FreshReference {
  ibl::CubeMapRGB rgb;
  std::vector<float> alpha;
  ibl::CubeMapRGB arithmetic;            // per texel and channel, linear
  std::vector<float> alpha_arithmetic;   // per texel
};

enum class Method { kBlur, kSH9 };

// Uploads `environment` and updates the diffuse map with `method` at
// `new_weight`; fills `fresh` with the CPU reference of the new map alone.
bool updateWith(passes::EnvironmentMaps& maps, Method method, const ibl::CubeMapRGB& environment,
                const std::vector<float>* validity, float new_weight, FreshReference* fresh, std::string& error) {
  if (!maps.setReflection(environment, error, validity)) return false;
  const int n = maps.settings().diffuse_face_size;
  if (method == Method::kSH9) {
    std::vector<float> read_validity;
    const auto reflection = maps.readReflection(error, &read_validity);
    if (!reflection) return false;
    const ibl::SH9RGB sh = ibl::projectToSH9(*reflection, &read_validity);
    if (!maps.updateDiffuseFromSH9(sh, error, new_weight)) return false;
    if (fresh != nullptr) {
      fresh->rgb = ibl::sh9DiffuseMap(sh, n);
      fresh->alpha.assign(static_cast<size_t>(ibl::kCubeFaceCount) * n * n, 1.0f);
      fresh->arithmetic = ibl::CubeMapRGB(n);
      for (auto& face : fresh->arithmetic.faces) std::fill(face.begin(), face.end(), glm::vec3(sh9EvaluationTolerance(sh)));
      fresh->alpha_arithmetic.assign(fresh->alpha.size(), 0.0f);
    }
    return true;
  }
  if (!maps.updateDiffuse(error, new_weight)) return false;
  if (fresh != nullptr) {
    // ibl::irradianceOverPiByCosinePasses on the reflection map as the GPU
    // holds it (read back), with the bound of cosine_irradiance_reference.hpp
    // (everything but the output's own rounding, which the callers add).
    std::vector<float> read_validity;
    const auto reflection = maps.readReflection(error, &read_validity);
    if (!reflection) return false;
    test::CosineReference ref =
        test::cosineIrradianceReference(*reflection, read_validity, maps.settings(), maps.storage(),
                                        maps.reflection().linear_scale, 0.0, fragmentUnitRoundoff());
    fresh->rgb = std::move(ref.rgb);
    fresh->alpha = std::move(ref.alpha);
    fresh->arithmetic = std::move(ref.tolerance);
    fresh->alpha_arithmetic = std::move(ref.alpha_tolerance);
  }
  return true;
}

class DiffuseBlendTest : public GpuTest, public ::testing::WithParamInterface<std::tuple<bool, Method>> {
 protected:
  std::optional<passes::EnvironmentMaps> makeMaps() {
    const bool force_8bit = std::get<0>(GetParam());
    const gles::Capabilities caps =
        force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
    std::string error;
    std::optional<passes::EnvironmentMaps> maps(std::in_place);
    EXPECT_TRUE(maps->init(caps, {}, error)) << error;
    if (!force_8bit && maps->storage() != passes::CubeStorage::kLinearHalfFloat) return std::nullopt;
    return maps;
  }
  Method method() const { return std::get<1>(GetParam()); }
};

// Weight 1 replaces the map: after any previous map, the result is
// bit-identical to that of maps that never had one (the blend branch is not
// taken, the scale is the new map's alone).
TEST_P(DiffuseBlendTest, WeightOneEqualsTheUnblendedResult) {
  auto blended = makeMaps();
  if (!blended) GTEST_SKIP() << "this GPU cannot render half floats";
  auto fresh = makeMaps();
  std::string error;
  const int size = blended->settings().reflection_face_size;
  std::vector<float> validity;
  const ibl::CubeMapRGB before = roomWithLamp(size, 1.0, &validity);
  const ibl::CubeMapRGB after = roomWithLamp(size, 2.0);
  ASSERT_TRUE(updateWith(*blended, Method::kBlur, before, &validity, 1.0f, nullptr, error)) << error;
  ASSERT_TRUE(updateWith(*blended, method(), after, nullptr, 1.0f, nullptr, error)) << error;
  ASSERT_TRUE(updateWith(*fresh, method(), after, nullptr, 1.0f, nullptr, error)) << error;
  const auto a = readDiffuseState(*blended, error);
  ASSERT_TRUE(a) << error;
  const auto b = readDiffuseState(*fresh, error);
  ASSERT_TRUE(b) << error;
  EXPECT_EQ(a->scale, b->scale);
  EXPECT_EQ(a->alpha, b->alpha);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) EXPECT_EQ(a->rgb.faces[face], b->rgb.faces[face]);
  // Out-of-range weights are refused with a message, and change nothing.
  EXPECT_FALSE(blended->updateDiffuse(error, 1.5f));
  EXPECT_NE(error.find("new_weight"), std::string::npos) << error;
  EXPECT_FALSE(blended->updateDiffuseFromSH9(ibl::SH9RGB{}, error, std::nanf("")));
}

// A step change: the room with a blind spot (previous map, made by the blur,
// alpha < 1 near the hole), then the whole room twice as bright, blended in at
// w = 0.3. Each texel must be previous + w (fresh - previous), rgb and alpha,
// with `previous` as read back and `fresh` the CPU reference of the new map
// alone. Tolerance: the result's storage rounding at its scale
// (storageTolerance) + w * the fresh map's shader error + (1 - w) * the
// shader's fetch and decode of the previous byte (RGBA8: kPreviousFetchLevels
// at the previous scale) + fp32 mix (4u of the values).
//
// kPreviousFetchLevels: llvmpipe's RGBA8 cube fetch returns some bytes a
// little low (here 213 and 223 come back ~0.15 level under byte / 255, seen
// in alpha, where no pow is involved: 0.7 * 223 + 76.5 = 232.6 is stored as
// 232), and the decode's approximate pow adds up to 0.1 level for rgb;
// 0.25 level bounds both.
constexpr double kPreviousFetchLevels = 0.25;
TEST_P(DiffuseBlendTest, StepChangeBlendsLinearly) {
  auto maps = makeMaps();
  if (!maps) GTEST_SKIP() << "this GPU cannot render half floats";
  std::string error;
  constexpr float kWeight = 0.3f;
  const int size = maps->settings().reflection_face_size;
  std::vector<float> validity;
  ASSERT_TRUE(updateWith(*maps, Method::kBlur, roomWithLamp(size, 1.0, &validity), &validity, 1.0f, nullptr, error))
      << error;
  const auto previous = readDiffuseState(*maps, error);
  ASSERT_TRUE(previous) << error;
  float min_previous_alpha = 1.0f;
  for (float a : previous->alpha) min_previous_alpha = std::min(min_previous_alpha, a);
  ASSERT_LT(min_previous_alpha, 0.9f);  // the hole shows in alpha, so alpha blending is exercised

  FreshReference fresh;
  const ibl::CubeMapRGB doubled = roomWithLamp(size, 2.0);
  ASSERT_TRUE(updateWith(*maps, method(), doubled, nullptr, kWeight, &fresh, error)) << error;
  const auto result = readDiffuseState(*maps, error);
  ASSERT_TRUE(result) << error;
  if (method() == Method::kBlur) {
    // This test is about the blend. The cosine passes are checked against
    // their CPU reference in cosine_irradiance_test.cpp; here the fresh map
    // is what the same GPU passes make at weight 1 (on a second set of maps),
    // so that a tap landing on a cube-face edge, where GPU and CPU may pick
    // different faces, cannot pass for a blending error. The blend mixes the
    // unrounded fresh value, so the fresh map's own storage rounding is the
    // arithmetic allowance.
    auto fresh_maps = makeMaps();
    ASSERT_TRUE(fresh_maps);
    ASSERT_TRUE(updateWith(*fresh_maps, Method::kBlur, doubled, nullptr, 1.0f, nullptr, error)) << error;
    const auto fresh_state = readDiffuseState(*fresh_maps, error);
    ASSERT_TRUE(fresh_state) << error;
    fresh.rgb = fresh_state->rgb;
    fresh.alpha = fresh_state->alpha;
    fresh.arithmetic = ibl::CubeMapRGB(fresh.rgb.face_size);
    for (int face = 0; face < ibl::kCubeFaceCount; ++face)
      for (size_t i = 0; i < fresh.rgb.faces[face].size(); ++i)
        for (int c = 0; c < 3; ++c)
          fresh.arithmetic.faces[face][i][c] =
              static_cast<float>(storageTolerance(fresh_maps->storage(), fresh.rgb.faces[face][i][c], fresh_state->scale));
    fresh.alpha_arithmetic.assign(fresh.alpha.size(), static_cast<float>(alphaTolerance(fresh_maps->storage())));
  }
  ASSERT_TRUE(test::allFinite(result->rgb));

  const passes::CubeStorage storage = maps->storage();
  const double u = fragmentUnitRoundoff();
  const int n = maps->settings().diffuse_face_size;
  ibl::CubeMapRGB expected(n);
  std::vector<float> expected_alpha(fresh.alpha.size());
  double max_error = 0.0;
  double max_excess = -1e9;
  double max_alpha_excess = -1e9;
  // What fixed-function blending (GL_CONSTANT_ALPHA) of the RGBA8 bytes
  // would give instead, both maps encoded on the result's scale.
  double byte_blend_mean = 0.0;
  double byte_blend_max = 0.0;
  int byte_blend_count = 0;
  double linear_relative_max = 0.0;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const size_t i = static_cast<size_t>(face) * n * n + static_cast<size_t>(y) * n + x;
        for (int c = 0; c < 3; ++c) {
          const double prev = previous->rgb.texel(face, x, y)[c];
          const double now = fresh.rgb.texel(face, x, y)[c];
          const double want = prev + kWeight * (now - prev);
          double tolerance = storageTolerance(storage, want, result->scale) + kWeight * fresh.arithmetic.texel(face, x, y)[c] +
                             4.0 * u * std::max(std::abs(prev), std::abs(now));
          if (storage == passes::CubeStorage::kSrgb8) {
            const double encoded = ibl::linearToSrgb(prev / previous->scale);
            tolerance += (1.0 - kWeight) * previous->scale *
                         test::srgbDecodeSlope(std::min(1.0, encoded + kPreviousFetchLevels / 255.0)) *
                         kPreviousFetchLevels / 255.0;
          }
          const double error_linear = std::abs(result->rgb.texel(face, x, y)[c] - want);
          max_error = std::max(max_error, error_linear);
          max_excess = std::max(max_excess, error_linear - tolerance);
          if (want > 0.01 * result->scale) {
            linear_relative_max = std::max(linear_relative_max, error_linear / want);
            const double s = result->scale;
            const double bytes = kWeight * ibl::linearToSrgb(now / s) + (1.0 - kWeight) * ibl::linearToSrgb(prev / s);
            const double relative = std::abs(ibl::srgbToLinear(bytes) * s - want) / want;
            byte_blend_mean += relative;
            byte_blend_max = std::max(byte_blend_max, relative);
            ++byte_blend_count;
          }
        }
        const double want_alpha = previous->alpha[i] + kWeight * (fresh.alpha[i] - previous->alpha[i]);
        double alpha_tolerance = alphaTolerance(storage) + kWeight * fresh.alpha_arithmetic[i] + 4.0 * u;
        if (storage == passes::CubeStorage::kSrgb8) alpha_tolerance += (1.0 - kWeight) * kPreviousFetchLevels / 255.0;
        max_alpha_excess = std::max(max_alpha_excess, std::abs(result->alpha[i] - want_alpha) - alpha_tolerance);
      }
    }
  }
  std::printf("[ measure  ] blend w=%.1f after a doubling, %s, %s: max |GPU - expected| %.2e (max relative %.2f%%), "
              "scale %.2f -> %.2f; blending sRGB bytes instead would be off by mean %.2f%%, max %.2f%%\n",
              kWeight, method() == Method::kSH9 ? "SH9" : "blur", maps->storageDescription().c_str(), max_error,
              100.0 * linear_relative_max, previous->scale, result->scale, 100.0 * byte_blend_mean / byte_blend_count,
              100.0 * byte_blend_max);
  EXPECT_LE(max_excess, 0.0);
  EXPECT_LE(max_alpha_excess, 0.0);
  if (storage == passes::CubeStorage::kSrgb8) {
    // The blended scale bounds the blend: w * new scale + (1 - w) * previous.
    double new_scale = 1.0;
    if (method() == Method::kBlur) {
      new_scale = maps->reflection().linear_scale;
    } else {
      for (const auto& face : fresh.rgb.faces) {
        for (const glm::vec3& t : face) new_scale = std::max<double>({new_scale, t.r, t.g, t.b});
      }
    }
    EXPECT_NEAR(result->scale, kWeight * new_scale + (1.0 - kWeight) * previous->scale, 1e-5 * result->scale);
  }
}

// Repeating the same new map at weight w converges geometrically, (1 - w)^k,
// but a stored map can only move by whole steps: an update changes the
// stored value only while w * |fresh - stored| exceeds half a step (plus the
// shader's 0.1-level encode error in RGBA8). So it stops within
// (0.5 + 0.1) / w steps of the fresh value: 2 levels at w = 0.3 in RGBA8;
// for half floats 0.5 ulp / w = 2^-11 / 0.3 relative. After 30 updates
// (0.7^30 = 2e-5 of the step left) the map must be inside that band (+ the
// fresh map's own storage rounding and arithmetic). The RGBA8 band is a
// property of any 8-bit IIR filter, blended in a shader or by GL.
TEST_P(DiffuseBlendTest, RepeatedUpdatesConvergeToTheDeadBand) {
  auto maps = makeMaps();
  if (!maps) GTEST_SKIP() << "this GPU cannot render half floats";
  std::string error;
  constexpr float kWeight = 0.3f;
  const int size = maps->settings().reflection_face_size;
  ASSERT_TRUE(updateWith(*maps, method(), roomWithLamp(size, 1.0), nullptr, 1.0f, nullptr, error)) << error;
  FreshReference fresh;
  const ibl::CubeMapRGB doubled = roomWithLamp(size, 2.0);
  std::vector<double> blended_ms;
  for (int k = 0; k < 30; ++k) {
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    ASSERT_TRUE(updateWith(*maps, method(), doubled, nullptr, kWeight, k == 29 ? &fresh : nullptr, error)) << error;
    glFinish();
    blended_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  const auto result = readDiffuseState(*maps, error);
  ASSERT_TRUE(result) << error;
  std::vector<double> unblended_ms;
  for (int k = 0; k < 7; ++k) {
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    ASSERT_TRUE(updateWith(*maps, method(), doubled, nullptr, 1.0f, nullptr, error)) << error;
    glFinish();
    unblended_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  const passes::CubeStorage storage = maps->storage();
  const int n = maps->settings().diffuse_face_size;
  double worst_levels = 0.0;
  double worst_relative = 0.0;
  double max_excess = -1e9;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        for (int c = 0; c < 3; ++c) {
          const double want = fresh.rgb.texel(face, x, y)[c];
          const double got = result->rgb.texel(face, x, y)[c];
          const double error_linear = std::abs(got - want);
          double tolerance = fresh.arithmetic.texel(face, x, y)[c] + 2e-5 * std::abs(want);  // + the 0.7^30 remainder
          if (storage == passes::CubeStorage::kSrgb8) {
            const double levels =
                255.0 * std::abs(ibl::linearToSrgb(got / result->scale) - ibl::linearToSrgb(want / result->scale));
            worst_levels = std::max(worst_levels, levels);
            const double band_levels = 0.6 / kWeight + 0.6;  // dead band + the final rounding
            const double encoded = ibl::linearToSrgb(std::max(0.0, want) / result->scale);
            tolerance += result->scale * test::srgbDecodeSlope(std::min(1.0, encoded + band_levels / 255.0)) *
                         band_levels / 255.0;
          } else {
            tolerance += std::abs(want) * std::ldexp(1.0, -11) * (1.0 / kWeight + 1.0);
          }
          if (want > 0.0) worst_relative = std::max(worst_relative, error_linear / want);
          max_excess = std::max(max_excess, error_linear - tolerance);
        }
      }
    }
  }
  std::printf("[ measure  ] %s %s: after 30 updates at w=%.1f, worst %.2f 8-bit levels / %.3f%% from the new map; "
              "update %.2f ms blended vs %.2f ms unblended (median, incl. upload of the 64^2 map)\n",
              method() == Method::kSH9 ? "SH9" : "blur", maps->storageDescription().c_str(), kWeight, worst_levels,
              100.0 * worst_relative, medianMs(blended_ms), medianMs(unblended_ms));
  EXPECT_LE(max_excess, 0.0);
}

// The camera's exposure and white balance moved between two updates: the
// same room, seen 2 stops darker with red x1.3 and blue x0.8, is blended at
// w = 0.3 with the previous map brought into the new units
// (setPreviousDiffuseUnits), so the result is the darker room's own map, as
// the same passes make it at weight 1. Without the units it would be
// 0.3 x 0.25 + 0.7 = 0.78 of the old map's green, three times too bright.
// Tolerance: both maps' storage rounding and 1% for the shader's arithmetic
// on two slightly different inputs.
TEST_P(DiffuseBlendTest, ThePreviousMapIsBlendedInTheNewUnits) {
  auto maps = makeMaps();
  if (!maps) GTEST_SKIP() << "this GPU cannot render half floats";
  auto fresh_maps = makeMaps();
  std::string error;
  const int size = maps->settings().reflection_face_size;
  const glm::vec3 units(0.25f * 1.3f, 0.25f, 0.25f * 0.8f);
  const ibl::CubeMapRGB room = roomWithLamp(size, 1.0);
  ibl::CubeMapRGB darker = room;
  for (auto& face : darker.faces)
    for (glm::vec3& texel : face) texel *= units;
  ASSERT_TRUE(updateWith(*maps, method(), room, nullptr, 1.0f, nullptr, error)) << error;
  maps->setPreviousDiffuseUnits(units);
  ASSERT_TRUE(updateWith(*maps, method(), darker, nullptr, 0.3f, nullptr, error)) << error;
  ASSERT_TRUE(updateWith(*fresh_maps, method(), darker, nullptr, 1.0f, nullptr, error)) << error;
  const auto blended = readDiffuseState(*maps, error);
  ASSERT_TRUE(blended) << error;
  const auto fresh = readDiffuseState(*fresh_maps, error);
  ASSERT_TRUE(fresh) << error;
  const passes::CubeStorage storage = maps->storage();
  double worst = 0.0;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (size_t i = 0; i < fresh->rgb.faces[face].size(); ++i)
      for (int c = 0; c < 3; ++c) {
        const double want = fresh->rgb.faces[face][i][c], got = blended->rgb.faces[face][i][c];
        const double tolerance = storageTolerance(storage, want, fresh->scale) +
                                 storageTolerance(storage, got, blended->scale) + 0.01 * std::abs(want);
        EXPECT_NEAR(got, want, tolerance) << "face " << face << " texel " << i << " channel " << c;
        worst = std::max(worst, std::abs(got - want) / std::max(1e-6, std::abs(want)));
      }
  std::cout << "blended in the new units: worst relative difference " << worst << "\n";
}

INSTANTIATE_TEST_SUITE_P(
    StorageAndMethod, DiffuseBlendTest,
    ::testing::Combine(::testing::Values(false, true), ::testing::Values(Method::kBlur, Method::kSH9)),
    [](const ::testing::TestParamInfo<std::tuple<bool, Method>>& info) {
      return std::string(std::get<0>(info.param) ? "Forced8Bit" : "Native") +
             (std::get<1>(info.param) == Method::kSH9 ? "SH9" : "Blur");
    });

}  // namespace
}  // namespace probelight
