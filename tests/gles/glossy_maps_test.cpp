// EnvironmentMaps::updateGlossy (prefilter, east cos^(n+1), north cos^n with
// the pole correction, normalised by coverage) against ibl::glossyMap, for
// both cube storages, with a lamp near the zenith (the pole correction
// carries it) on the analytic sky.
//
// Tolerance. The reference is computed from the reflection map as read back
// (exactly the GPU's input), so only what the GPU adds is bounded:
//  - storage of the prefiltered, intermediate and glossy maps. Half floats:
//    2^-11 relative each; every pass is a weighted mean with non-negative
//    normalised weights, which keeps a relative error relative, so 3 * 2^-11
//    of the result. RGBA8 at the reflection's scale S: e(v) = 0.7 level of the
//    sRGB code at v (0.5 rounding, 0.1 each for the shader's approximate pow
//    in encode and decode, as in cosine_irradiance_reference.hpp; the
//    output's is its own 0.5 + 0.1). e is constant on the sRGB curve's
//    linear segment and increasing and concave above it, so e + e(0) bounds
//    its concave envelope, and by Jensen the weighted mean of e over a
//    footprint is <= e(mean) + e(0): each stored stage adds at most
//    e(result) + e(0);
//  - fp32 tap directions (~1e-5 rad: normalize, cross, sin/cos) move a
//    bilinear sample by 1e-5 * 64 texels at most, changing it by that times
//    the largest value near it: the lamp's within its reach, the sky's
//    (<= 1.1) elsewhere;
//  - fp32 sums and weights (exp of a series, relative 1e-6): 40 u.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "cosine_irradiance_reference.hpp"
#include "gles_test_support.hpp"
#include "ibl/glossy_maps.hpp"
#include "passes/environment_maps.hpp"

namespace probelight {
namespace {

using test::GpuTest;

const glm::dvec3 kLamp = glm::normalize(glm::dvec3(0.06, -0.04, 1.0));
constexpr double kLampRadiusRad = 4.0 * M_PI / 180.0;

ibl::CubeMapRGB lampRoom(int face_size, double gain) {
  ibl::CubeMapRGB cube(face_size);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < face_size; ++y)
      for (int x = 0; x < face_size; ++x) {
        const glm::dvec3 d = ibl::cubeTexelCenterDirection(face, x, y, face_size);
        glm::dvec3 v = test::analyticEnvironment(d);
        if (glm::dot(d, kLamp) > std::cos(kLampRadiusRad)) v += gain * glm::dvec3(1.0, 0.9, 0.8);
        cube.texel(face, x, y) = glm::vec3(v);
      }
  return cube;
}

class GlossyMapsTest : public GpuTest, public ::testing::WithParamInterface<bool> {};

TEST_P(GlossyMapsTest, MatchesCpuReference) {
  const bool force_8bit = GetParam();
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  std::string error;
  passes::EnvironmentMaps maps;
  const passes::EnvironmentMapSettings settings;
  ASSERT_TRUE(maps.init(caps, settings, error)) << error;
  if (!force_8bit && maps.storage() != passes::CubeStorage::kLinearHalfFloat)
    GTEST_SKIP() << maps.storageDescription();
  // 8-bit maps hold up to their brightest texel; a 10x lamp keeps the sky
  // tens of levels deep (as cosine_irradiance_test.cpp).
  const double gain = force_8bit ? 10.0 : 50.0;
  ASSERT_TRUE(maps.setReflection(lampRoom(settings.reflection_face_size, gain), error)) << error;
  std::vector<double> times;
  for (int run = 0; run < 5; ++run) {
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    ASSERT_TRUE(maps.updateGlossy(error)) << error;
    glFinish();
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  std::vector<float> input_validity;
  const auto input = maps.readReflection(error, &input_validity);
  ASSERT_TRUE(input) << error;
  const double scale = maps.reflection().linear_scale;
  const gles::Capabilities& c = test::sharedCapabilities();
  const int bits = c.fragment_highp ? c.fragment_highp_mantissa_bits : c.fragment_mediump_mantissa_bits;
  const double u = std::ldexp(1.0, -(std::max(bits, 10) + 1));
  for (int level = 0; level < settings.glossy_levels; ++level) {
    const ibl::GlossyLevelSettings lobe = passes::glossyLevelSettings(settings, level);
    const ibl::CubeMapRGB want = ibl::glossyMap(*input, lobe, &input_validity);
    std::vector<float> alpha;
    const auto got = maps.readGlossy(level, error, &alpha);
    ASSERT_TRUE(got) << error;
    ASSERT_TRUE(test::allFinite(*got));
    EXPECT_EQ(maps.glossy(level).linear_scale, maps.reflection().linear_scale);
    const double reach = std::cos(4.5 / std::sqrt(lobe.exponent) + kLampRadiusRad + 4.0 / lobe.output_face_size);
    double max_relative = 0.0, max_excess = -1e30, max_alpha_error = 0.0;
    const int n = lobe.output_face_size;
    for (int face = 0; face < ibl::kCubeFaceCount; ++face)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const glm::dvec3 r = ibl::cubeTexelCenterDirection(face, x, y, n);
          const double nearby_max = glm::dot(r, kLamp) > reach ? gain + 1.1 : 1.1;
          for (int ch = 0; ch < 3; ++ch) {
            const double v = want.texel(face, x, y)[ch];
            double storage;
            if (maps.storage() == passes::CubeStorage::kLinearHalfFloat) {
              storage = 3.0 * v * std::ldexp(1.0, -11);
            } else {
              const double e0 = test::storageRoundingBound(maps.storage(), 0.0, scale, 0.7);
              storage = 2.0 * (test::storageRoundingBound(maps.storage(), v, scale, 0.7) + e0) +
                        test::storageRoundingBound(maps.storage(), v, scale, 0.6);
            }
            const double tolerance = storage + 1e-5 * 64.0 * nearby_max + 40.0 * u * v;
            const double e = std::abs(got->texel(face, x, y)[ch] - v);
            max_relative = std::max(max_relative, e / v);
            max_excess = std::max(max_excess, e - tolerance);
          }
          max_alpha_error = std::max(max_alpha_error, std::abs(alpha[static_cast<size_t>(face) * n * n + y * n + x] - 1.0));
        }
    std::printf("[ measure  ] glossy level %d (n = %g, %d^2) %s, lamp %gx: max relative |GPU-CPU| %.3f%%, excess over "
                "tolerance %.2e\n",
                level, lobe.exponent, n, maps.storageDescription().c_str(), gain, 100.0 * max_relative, max_excess);
    EXPECT_LE(max_excess, 0.0);
    // Validity 1 everywhere: coverage is a mean of ones (1 in RGBA8 exactly, 2^-11 in half floats).
    EXPECT_LE(max_alpha_error, std::ldexp(1.0, -11));
  }
  std::printf("[ measure  ] updateGlossy (%d levels) %s: %.2f ms (median of 5)\n", settings.glossy_levels,
              maps.storageDescription().c_str(), times[times.size() / 2]);
}

INSTANTIATE_TEST_SUITE_P(Storage, GlossyMapsTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("Forced8Bit") : std::string("Native");
                         });

// Per level, for the timing table: one level at a time.
TEST_F(GpuTest, GlossyLevelTimes) {
  for (int levels : {1, 2}) {
    std::string error;
    passes::EnvironmentMaps maps;
    passes::EnvironmentMapSettings settings;
    settings.glossy_levels = levels;
    ASSERT_TRUE(maps.init(test::sharedCapabilities(), settings, error)) << error;
    ASSERT_TRUE(maps.setReflection(lampRoom(settings.reflection_face_size, 10.0), error)) << error;
    ASSERT_TRUE(maps.updateGlossy(error)) << error;  // warm-up (shader JIT)
    std::vector<double> times;
    for (int run = 0; run < 5; ++run) {
      glFinish();
      const auto start = std::chrono::steady_clock::now();
      ASSERT_TRUE(maps.updateGlossy(error)) << error;
      glFinish();
      times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(times.begin(), times.end());
    std::printf("[ measure  ] updateGlossy with %d level(s): %.2f ms (median of 5, %s)\n", levels,
                times[times.size() / 2], maps.storageDescription().c_str());
  }
}

TEST_F(GpuTest, GlossySettingsAreChecked) {
  std::string error;
  passes::EnvironmentMaps maps;
  passes::EnvironmentMapSettings settings;
  settings.glossy_face_size[1] = 24;  // does not divide 64
  EXPECT_FALSE(maps.init(test::sharedCapabilities(), settings, error));
  EXPECT_NE(error.find("glossy_face_size"), std::string::npos) << error;
  settings = {};
  settings.glossy_levels = 3;
  EXPECT_FALSE(maps.init(test::sharedCapabilities(), settings, error));
  settings.glossy_levels = 0;
  ASSERT_TRUE(maps.init(test::sharedCapabilities(), settings, error)) << error;
  EXPECT_EQ(maps.glossyCube(0), 0u);
  EXPECT_FALSE(maps.readGlossy(0, error));
}

}  // namespace
}  // namespace probelight
