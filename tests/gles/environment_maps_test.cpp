// Stage 2 on the GPU against the CPU reference (ibl::probeImageToCubeMap),
// for both cube storages.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include <gtest/gtest.h>

#include "gles_test_support.hpp"
#include "test_scenes.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_to_cube.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"

namespace probelight {
namespace {

using test::GpuTest;
using test::bilinearNeighbourhoodRange;
using test::kProbeReflectance;
using test::renderBallImage;
using test::testBallView;

struct ProbeComparison {
  double max_error_levels = 0.0;    // |GPU - CPU| in 8-bit encoded levels
  double max_excess_levels = -1e9;  // worst (error - tolerance); must stay <= 0
  int validity_mismatches = 0;
  int visible_texels = 0;
  int unconverged_texels = 0;
  double max_truth_error_levels = 0.0;  // GPU vs the analytic environment
};

class ProbeToCubeTest : public GpuTest, public ::testing::WithParamInterface<bool> {};

// GPU vs CPU, compared in encoded units e = linearToSrgb(linear * reflectance),
// i.e. in the camera's own 8-bit scale:
//  - GLES filters 8-bit textures in fixed point: llvmpipe's lerp returns an
//    8-bit result (up to 1 level off the exact bilinear value, as a 1-level-
//    per-pixel ramp shows) and its weights have 8 fractional bits, which adds
//    up to range / 512, `range` being the spread of the four bytes read
//    (large only at the ball's silhouette, where the image jumps);
//  - storage: RGBA8 rounds the encoded value again (0.5 level); half floats
//    keep 11 bits of the linear value (< 0.05 level after encoding), plus
//    the shader's approximate pow (< 0.1 level measured on a flat image);
//  - fp32 geometry moves the sample by ~1e-4 px, i.e. < range * 1e-4 levels.
// Tolerance: 1.5 + range / 256 levels.
TEST_P(ProbeToCubeTest, MatchesCpuReferenceOnASyntheticBall) {
  const bool force_8bit = GetParam();
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  const ibl::MirrorBallView view = testBallView();
  const ImageRGB8 image = renderBallImage(view);
  std::string error;
  passes::CameraFrameTexture frame;
  ASSERT_TRUE(frame.init(caps, error)) << error;
  ASSERT_TRUE(frame.upload(image, error)) << error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(maps.init(caps, {}, error)) << error;
  if (!force_8bit && maps.storage() != passes::CubeStorage::kLinearHalfFloat) {
    GTEST_SKIP() << "this GPU cannot render half floats: " << maps.storageDescription();
  }
  const auto gpu_start = std::chrono::steady_clock::now();
  ASSERT_TRUE(maps.updateReflection(frame, view, kProbeReflectance, error)) << error;
  glFinish();
  const double gpu_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - gpu_start).count();
  std::vector<float> validity;
  const auto gpu = maps.readReflection(error, &validity);
  ASSERT_TRUE(gpu) << error;
  ASSERT_TRUE(test::allFinite(*gpu));

  ibl::ProbeToCubeParams params;
  params.face_size = maps.settings().reflection_face_size;
  params.probe_reflectance = kProbeReflectance;
  params.normal_iterations = maps.settings().normal_iterations;
  const ibl::CubeMapRGB cpu = ibl::probeImageToCubeMap(view, image, params);

  const glm::dvec3 ball_to_camera = glm::normalize(view.pose.cameraCenterWorld() - view.center_w);
  ProbeComparison result;
  const int n = params.face_size;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 direction = ibl::cubeTexelCenterDirection(face, x, y, n);
        const auto pixel = ibl::reflectedDirectionToPixel(view, direction, params.normal_iterations);
        const float alpha = validity[static_cast<size_t>(face * n * n + y * n + x)];
        const bool gpu_visible = alpha > 0.5f;
        if (gpu_visible != pixel.has_value()) {
          ++result.validity_mismatches;
          continue;
        }
        if (!pixel) {
          // Blind spot: 0, as on the CPU.
          EXPECT_EQ(gpu->texel(face, x, y), glm::vec3(0.0f));
          continue;
        }
        // Next to the blind spot the ball normal is at grazing incidence and
        // the fixed-point iteration's gain, (radius / distance) / (2 cos
        // incidence), exceeds 1: after the shared 4 steps the result has not
        // converged, and fp32 vs double rounding is amplified rather than
        // damped. Only converged texels are compared; the rest must be a thin rim.
        const auto converged_pixel = ibl::reflectedDirectionToPixel(view, direction, 32);
        if (!converged_pixel || glm::length(*converged_pixel - *pixel) > 0.05) {
          ++result.unconverged_texels;
          continue;
        }
        ++result.visible_texels;
        const glm::dvec3 range = bilinearNeighbourhoodRange(image, *pixel);
        for (int c = 0; c < 3; ++c) {
          const double gpu_levels = 255.0 * ibl::linearToSrgb(gpu->texel(face, x, y)[c] * kProbeReflectance);
          const double cpu_levels = 255.0 * ibl::linearToSrgb(cpu.texel(face, x, y)[c] * kProbeReflectance);
          const double error_levels = std::abs(gpu_levels - cpu_levels);
          result.max_error_levels = std::max(result.max_error_levels, error_levels);
          result.max_excess_levels = std::max(result.max_excess_levels, error_levels - (1.5 + range[c] / 256.0));
        }
        // Independent check against the truth the image was made from, for
        // directions the ball shows well (within 90 deg of the camera, i.e.
        // ball normals within 45 deg of the view ray, >= 0.7 of the radius
        // from the silhouette). Error budget: the camera's own rounding
        // (0.5 level) plus bilinear interpolation of the environment across
        // ~0.1 rad per pixel: curvature * step^2 / 8 < 1 level here.
        if (glm::dot(direction, ball_to_camera) > 0.0) {
          const glm::dvec3 truth = test::analyticEnvironment(direction) * kProbeReflectance;
          for (int c = 0; c < 3; ++c) {
            const double gpu_levels = 255.0 * ibl::linearToSrgb(gpu->texel(face, x, y)[c] * kProbeReflectance);
            result.max_truth_error_levels =
                std::max(result.max_truth_error_levels, std::abs(gpu_levels - 255.0 * ibl::linearToSrgb(truth[c])));
          }
        }
      }
    }
  }
  std::printf("[ measure  ] probe->cube %s: max |GPU-CPU| %.3f levels, max vs truth %.3f levels, %d visible, "
              "%d validity mismatches, %d unconverged, %.2f ms GPU (6x%d^2)\n",
              maps.storageDescription().c_str(), result.max_error_levels, result.max_truth_error_levels,
              result.visible_texels, result.validity_mismatches, result.unconverged_texels, gpu_ms, n);
  EXPECT_LT(result.unconverged_texels, result.visible_texels / 50);
  EXPECT_LE(result.max_excess_levels, 0.0);
  // The ball shows more than half the sphere of directions.
  EXPECT_GT(result.visible_texels, 3 * n * n);
  // Visibility flips only where |n . v| ~ 0 within fp32 rounding: a handful
  // of texels on the blind spot's rim at most.
  EXPECT_LE(result.validity_mismatches, 4);
  EXPECT_LT(result.max_truth_error_levels, 2.0);
}

INSTANTIATE_TEST_SUITE_P(Storage, ProbeToCubeTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("Forced8Bit") : std::string("Native");
                         });

// A camera configured with a plain power-law transfer: the shader decodes
// with the same curve as the CPU reference, compared in that curve's own
// 8-bit levels (the same budget as above: llvmpipe's 8-bit filter and the
// storage rounding, 1.5 + range / 256 levels), and the choice really reaches
// the shader (mid-tones differ from the sRGB decode by far more).
class ProbeToCubeTransfer : public GpuTest {};

TEST_F(ProbeToCubeTransfer, GammaCurveMatchesTheCpuReference) {
  const gles::Capabilities caps = test::sharedCapabilities();
  const ibl::MirrorBallView view = testBallView();
  const ImageRGB8 image = renderBallImage(view);
  std::string error;
  passes::CameraFrameTexture frame;
  ASSERT_TRUE(frame.init(caps, error) && frame.upload(image, error)) << error;
  passes::EnvironmentMapSettings settings;
  settings.camera_transfer = {ibl::CameraTransfer::Curve::kGamma, 1.8};
  passes::EnvironmentMaps gamma_maps, srgb_maps;
  ASSERT_TRUE(gamma_maps.init(caps, settings, error)) << error;
  ASSERT_TRUE(srgb_maps.init(caps, {}, error)) << error;
  ASSERT_TRUE(gamma_maps.updateReflection(frame, view, kProbeReflectance, error)) << error;
  ASSERT_TRUE(srgb_maps.updateReflection(frame, view, kProbeReflectance, error)) << error;
  std::vector<float> validity;
  const auto gamma_gpu = gamma_maps.readReflection(error, &validity);
  const auto srgb_gpu = srgb_maps.readReflection(error);
  ASSERT_TRUE(gamma_gpu && srgb_gpu) << error;

  ibl::ProbeToCubeParams params;
  params.face_size = settings.reflection_face_size;
  params.probe_reflectance = kProbeReflectance;
  params.normal_iterations = settings.normal_iterations;
  params.camera_transfer = settings.camera_transfer;
  const ibl::CubeMapRGB cpu = ibl::probeImageToCubeMap(view, image, params);

  auto levels = [](double linear) { return 255.0 * std::pow(std::clamp(linear * kProbeReflectance, 0.0, 1.0), 1.0 / 1.8); };
  // The 8-bit storage (a bare GLES2 context: scripts/gpu-profiles.sh) holds
  // a texel to within half an sRGB code of value / linear_scale: that step,
  // in the gamma curve's levels, adds to the tolerance; half floats add
  // nothing at this scale.
  const double scale = gamma_maps.reflection().linear_scale;
  const bool stored_in_8_bits = gamma_maps.storage() == passes::CubeStorage::kSrgb8;
  auto storageStepLevels = [&](double linear) {
    if (!stored_in_8_bits) return 0.0;
    const int code = ibl::linearToSrgbCode(std::clamp(linear / scale, 0.0, 1.0));
    const double below = ibl::srgbCodeToLinear(static_cast<std::uint8_t>(std::max(code - 1, 0))) * scale;
    const double above = ibl::srgbCodeToLinear(static_cast<std::uint8_t>(std::min(code + 1, 255))) * scale;
    return 0.5 * std::max(levels(above) - levels(linear), levels(linear) - levels(below));
  };
  const int n = params.face_size;
  double max_excess = -1e9;
  double max_curve_difference = 0.0;
  int compared = 0;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 direction = ibl::cubeTexelCenterDirection(face, x, y, n);
        const auto pixel = ibl::reflectedDirectionToPixel(view, direction, params.normal_iterations);
        const auto converged = ibl::reflectedDirectionToPixel(view, direction, 32);
        if (validity[static_cast<size_t>(face * n * n + y * n + x)] < 0.5f || !pixel || !converged ||
            glm::length(*converged - *pixel) > 0.05)
          continue;  // blind spot and its unconverged rim, as in the test above
        const glm::dvec3 range = bilinearNeighbourhoodRange(image, *pixel);
        for (int c = 0; c < 3; ++c) {
          const double error_levels = std::abs(levels(gamma_gpu->texel(face, x, y)[c]) - levels(cpu.texel(face, x, y)[c]));
          max_excess = std::max(max_excess, error_levels - (1.5 + range[c] / 256.0 +
                                                            storageStepLevels(cpu.texel(face, x, y)[c])));
          max_curve_difference = std::max(
              max_curve_difference, static_cast<double>(std::abs(gamma_gpu->texel(face, x, y)[c] - srgb_gpu->texel(face, x, y)[c]) /
                                        std::max(1e-3f, srgb_gpu->texel(face, x, y)[c])));
        }
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 3 * n * n);
  EXPECT_LE(max_excess, 0.0);
  // Gamma 1.8 against sRGB differs by >= 20% somewhere in the mid-tones.
  EXPECT_GT(max_curve_difference, 0.2);
}

// Stage 3 (the diffuse map) is tested against ibl::irradianceOverPiByCosinePasses
// in cosine_irradiance_test.cpp.

}  // namespace
}  // namespace probelight
