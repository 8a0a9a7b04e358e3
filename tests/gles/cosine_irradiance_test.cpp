// Stage 3 on the GPU (EnvironmentMaps::updateDiffuse: prefilter, east cos^2
// and north cos on latitude-longitude maps, resampling to the cube,
// normalised convolution of validity)
// against ibl::irradianceOverPiByCosinePasses, for both cube storages. The
// tolerance is derived in cosine_irradiance_reference.hpp.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "cosine_irradiance_reference.hpp"
#include "gles_test_support.hpp"
#include "test_scenes.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/spherical_blur.hpp"
#include "passes/environment_maps.hpp"

namespace probelight {
namespace {

using test::GpuTest;
using test::kBlindSpot;
using test::kZenithLamp;
using test::kZenithLampRadiusRad;
using test::zenithLampRoom;

double fragmentUnitRoundoff() {
  const gles::Capabilities& caps = test::sharedCapabilities();
  const int bits = caps.fragment_highp ? caps.fragment_highp_mantissa_bits : caps.fragment_mediump_mantissa_bits;
  return std::ldexp(1.0, -(std::max(bits, 10) + 1));
}

struct IrradianceComparison {
  double max_error = 0.0;           // |GPU - CPU|, linear
  double max_relative = 0.0;        // over texels >= 1% of the scale
  double max_excess = -1e30;        // error - tolerance; must stay <= 0
  double max_alpha_excess = -1e30;
  double max_tolerance_relative = 0.0;
  double ms = 0.0;
  float scale = 1.0f;
  passes::CubeStorage storage = passes::CubeStorage::kSrgb8;
  std::string description;
};

// Uploads the zenith-lamp room, runs updateDiffuse (timed: median of 5) on
// maps made with `gpu_settings`, and compares with the CPU reference made
// with `cpu_settings`. Output rounding: RGBA8 0.5 level + 0.1 level of the
// shader's approximate pow in the encode, at the diffuse map's scale; half
// floats 2^-11 relative; alpha 0.5 / 255 or 2^-11.
std::optional<IrradianceComparison> runComparison(bool force_8bit, double lamp_gain,
                                        const passes::EnvironmentMapSettings& gpu_settings,
                                        const passes::EnvironmentMapSettings& cpu_settings, std::string& error) {
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  passes::EnvironmentMaps maps;
  if (!maps.init(caps, gpu_settings, error)) return std::nullopt;
  IrradianceComparison result;
  result.storage = maps.storage();
  result.description = maps.storageDescription();
  if (!force_8bit && maps.storage() != passes::CubeStorage::kLinearHalfFloat) {
    error = "skip: " + maps.storageDescription();
    return std::nullopt;
  }
  std::vector<float> validity;
  const ibl::CubeMapRGB room = zenithLampRoom(gpu_settings.reflection_face_size, lamp_gain, validity);
  if (!maps.setReflection(room, error, &validity)) return std::nullopt;
  std::vector<double> times;
  for (int run = 0; run < 5; ++run) {
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    if (!maps.updateDiffuse(error)) return std::nullopt;
    glFinish();
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  result.ms = times[times.size() / 2];
  std::vector<float> alpha;
  const auto gpu = maps.readDiffuse(error, &alpha);
  if (!gpu) return std::nullopt;
  if (!test::allFinite(*gpu)) {
    error = "non-finite texels";
    return std::nullopt;
  }
  result.scale = maps.diffuse().linear_scale;
  // The map as uploaded, not read back: its upload rounding (0.5 level) is part of the tolerance.
  const test::CosineReference ref =
      test::cosineIrradianceReference(room, validity, cpu_settings, maps.storage(), maps.reflection().linear_scale,
                                      0.5, fragmentUnitRoundoff());
  const int n = cpu_settings.diffuse_face_size;
  const double alpha_output = result.storage == passes::CubeStorage::kSrgb8 ? 0.5 / 255.0 : std::ldexp(1.0, -11);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const size_t i = static_cast<size_t>(face) * n * n + static_cast<size_t>(y) * n + x;
        for (int c = 0; c < 3; ++c) {
          const double want = ref.rgb.texel(face, x, y)[c];
          const double error_linear = std::abs(gpu->texel(face, x, y)[c] - want);
          const double tolerance = ref.tolerance.texel(face, x, y)[c] +
                                   test::storageRoundingBound(result.storage, want, result.scale, 0.6);
          result.max_error = std::max(result.max_error, error_linear);
          result.max_excess = std::max(result.max_excess, error_linear - tolerance);
          if (want > 0.01 * result.scale) {
            result.max_relative = std::max(result.max_relative, error_linear / want);
            result.max_tolerance_relative = std::max(result.max_tolerance_relative, tolerance / want);
          }
        }
        result.max_alpha_excess =
            std::max(result.max_alpha_excess,
                     std::abs(static_cast<double>(alpha[i]) - ref.alpha[i]) - ref.alpha_tolerance[i] - alpha_output);
      }
    }
  }
  return result;
}

// Lamp 100x the brightest sky in half floats (HDR); 10x in RGBA8, whose
// scale is the brightest texel, so a brighter lamp would leave the sky only
// a few sRGB levels (setReflection's scale; camera maps have <= 1/reflectance).
double lampGain(bool force_8bit) { return force_8bit ? 10.0 : 100.0; }

class CosineIrradianceTest : public GpuTest, public ::testing::WithParamInterface<bool> {};

TEST_P(CosineIrradianceTest, MatchesCpuReferenceWithZenithLampAndBlindSpot) {
  const bool force_8bit = GetParam();
  std::string error;
  const passes::EnvironmentMapSettings settings;
  const auto result = runComparison(force_8bit, lampGain(force_8bit), settings, settings, error);
  if (!result && error.rfind("skip: ", 0) == 0) GTEST_SKIP() << error;
  ASSERT_TRUE(result) << error;
  std::printf("[ measure  ] cosine irradiance %s, lamp %gx (scale %.2f): max |GPU-CPU| %.2e, max relative %.3f%% "
              "(tolerance up to %.3f%%), alpha excess %.1e; updateDiffuse %.2f ms (median of 5)\n",
              result->description.c_str(), lampGain(force_8bit), result->scale, result->max_error,
              100.0 * result->max_relative, 100.0 * result->max_tolerance_relative, result->max_alpha_excess, result->ms);
  EXPECT_LE(result->max_excess, 0.0);
  EXPECT_LE(result->max_alpha_excess, 0.0);
}

// The tolerance is tight enough to see a coarser east-pass map: the same GPU
// maps made with 16 rows instead of 32 must fail the comparison with the
// reference for 32. Half floats only: in RGBA8 at the lamp's scale the
// worst-case storage bound (four stored maps, ~2.3% each for the sky at
// scale 10.6) is larger than what the rows change there.
TEST_F(GpuTest, ACoarserLatitudeLongitudeMapFailsTheComparison) {
  std::string error;
  passes::EnvironmentMapSettings coarser;
  coarser.intermediate_rows = 16;
  const auto result = runComparison(false, lampGain(false), coarser, passes::EnvironmentMapSettings{}, error);
  if (!result && error.rfind("skip: ", 0) == 0) GTEST_SKIP() << error;
  ASSERT_TRUE(result) << error;
  std::printf("[ measure  ] 16 rows against the reference for 32, %s: max relative %.2f%%, excess over the tolerance %.2e\n",
              result->description.c_str(), 100.0 * result->max_relative, result->max_excess);
  EXPECT_GT(result->max_excess, 0.0);
}

// Nothing seen at all: coverage 0 everywhere, so rgb is 0 (not 0 / 0).
TEST_P(CosineIrradianceTest, BlindEverywhereGivesZero) {
  const bool force_8bit = GetParam();
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  std::string error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(maps.init(caps, {}, error)) << error;
  const int size = maps.settings().reflection_face_size;
  const std::vector<float> none(static_cast<size_t>(ibl::kCubeFaceCount) * size * size, 0.0f);
  ibl::CubeMapRGB dark(size);
  ASSERT_TRUE(maps.setReflection(dark, error, &none)) << error;
  ASSERT_TRUE(maps.updateDiffuse(error)) << error;
  std::vector<float> alpha;
  const auto gpu = maps.readDiffuse(error, &alpha);
  ASSERT_TRUE(gpu) << error;
  ASSERT_TRUE(test::allFinite(*gpu));
  for (const auto& face : gpu->faces)
    for (const glm::vec3& t : face) ASSERT_EQ(t, glm::vec3(0.0f));
  for (float a : alpha) ASSERT_EQ(a, 0.0f);
}

INSTANTIATE_TEST_SUITE_P(Storage, CosineIrradianceTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("Forced8Bit") : std::string("Native");
                         });

TEST_F(GpuTest, CosineIrradianceSettingsAreChecked) {
  std::string error;
  passes::EnvironmentMaps maps;
  passes::EnvironmentMapSettings settings;
  settings.prefilter_face_size = 24;  // does not divide 64
  EXPECT_FALSE(maps.init(test::sharedCapabilities(), settings, error));
  EXPECT_NE(error.find("prefilter_face_size"), std::string::npos) << error;
  settings = {};
  settings.intermediate_rows = 31;  // the north pass's taps need an even count
  EXPECT_FALSE(maps.init(test::sharedCapabilities(), settings, error));
  EXPECT_NE(error.find("intermediate_rows"), std::string::npos) << error;
}

}  // namespace
}  // namespace probelight
