// The frame's blur given to the object (passes/object_blur): a simulated
// frame with a lens blur, its blur measured on the tag (ibl/edge_blur), a
// flat sphere composited through the blur layer by that much; the sphere's
// silhouette then spreads as the tag's edge does. Both widths are measured
// the same way: a blurred step fitted across the edge, its 10-90% width.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/edge_blur.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/object_blur.hpp"
#include "passes/object_compositor.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

using test::GpuTest;

constexpr double kTenToNinetyPerSigma = 2.0 * 1.2815515655446004;

TEST(ObjectBlurWeights, AreANormalisedGaussianOfTheSigmaAsked) {
  for (double sigma : {0.4, 1.0, 2.5}) {
    const std::vector<float> w = passes::objectBlurWeights(sigma);
    double sum = w[0], variance = 0.0;
    for (size_t k = 1; k < w.size(); ++k) {
      sum += 2.0 * w[k];
      variance += 2.0 * static_cast<double>(k * k) * w[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6);
    // The weights' own variance is what was asked, below a pixel too
    // (where sampling a Gaussian of that sigma would give too little).
    EXPECT_NEAR(variance, sigma * sigma, 1e-4 * sigma * sigma) << sigma;
  }
  EXPECT_EQ(passes::objectBlurWeights(0.0).size(), 1u);
  EXPECT_EQ(passes::objectBlurWeights(100.0).size(), static_cast<size_t>(passes::kMaxObjectBlurTaps + 1));
  EXPECT_DOUBLE_EQ(passes::objectBlurSigmaPx(0.2), 0.0);
  EXPECT_NEAR(passes::objectBlurSigmaPx(1.0), std::sqrt(1.0 - 1.0 / 12.0), 1e-12);
  EXPECT_DOUBLE_EQ(passes::objectBlurSigmaPx(1.0, 0.0), 1.0);
}

// Phi((d - e) / s) fitted to a radial profile: the spread s by a scan over
// s and e, coarse and then fine around the best (levels fixed).
double fittedSpreadPx(const std::vector<std::pair<double, double>>& samples) {
  auto cost = [&](double s, double e) {
    double sum = 0.0;
    for (const auto& [d, level] : samples) {
      const double r = level - 0.5 * std::erfc(-(d - e) / (s * std::sqrt(2.0)));
      sum += r * r;
    }
    return sum;
  };
  double best_s = 1.0, best_e = 0.0, best = 1e300;
  auto scan = [&](double s0, double s1, double s_step, double e0, double e1, double e_step) {
    const double s_from = best_s, e_from = best_e;
    for (double s = s_from + s0; s <= s_from + s1; s += s_step)
      for (double e = e_from + e0; e <= e_from + e1; e += e_step)
        if (s > 0.02) {
          const double c = cost(s, e);
          if (c < best) {
            best = c;
            best_s = s;
            best_e = e;
          }
        }
  };
  scan(-0.95, 3.0, 0.05, -1.0, 1.0, 0.1);
  scan(-0.05, 0.05, 0.002, -0.1, 0.1, 0.01);
  return best_s;
}

class BlurredObject : public GpuTest, public ::testing::WithParamInterface<double> {};

TEST_P(BlurredObject, SilhouetteSpreadsAsTheTagsEdge) {
  // The frame's blur, from the tag of a simulated frame with this lens.
  sim::SceneConfig scene = sim::defaultScene();
  scene.lens_blur_sigma_px = GetParam();
  const sim::World world(scene);
  ImageRGB8 frame;
  FrameTruth truth;
  world.render(0, frame, truth);
  const ibl::EdgeBlurReading tag = ibl::measureEdgeBlur(
      scene.camera, truth.pose, scene.rig.tag_size_m / 2.0, scene.rig.tag_size_m / 8.0,
      [&frame](int x, int y) {
        const std::uint8_t* p = frame.row(y) + 3 * x;
        return glm::u8vec3(p[0], p[1], p[2]);
      },
      ibl::EdgeBlurSettings{});
  ASSERT_EQ(tag.status, ibl::EdgeBlurStatus::kMeasured) << tag.message;

  // A flat white sphere over a uniform grey, the camera on its axis (no
  // distortion): its silhouette is a circle of radius f R / sqrt(D^2 - R^2).
  CameraIntrinsics camera = scene.camera;
  camera.distortion = {0, 0, 0, 0, 0};
  const glm::dvec3 centre_w(0.0, 0.0, 0.04);
  const double radius_m = 0.04, distance_m = 0.6;
  const PoseCamFromWorld pose = test::lookAt(centre_w + glm::dvec3(0.0, -distance_m * 0.8, distance_m * 0.6), centre_w);
  const double radius_px = camera.fx_px * radius_m / std::sqrt(distance_m * distance_m - radius_m * radius_m);
  const glm::dvec2 centre_px(camera.cx_px, camera.cy_px);
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  gles::RenderTarget target;
  passes::CameraFrameTexture background;
  passes::EnvironmentMaps maps;
  passes::ObjectCompositor compositor;
  passes::ObjectBlurLayer blur;
  ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
  ASSERT_TRUE(background.init(caps, error)) << error;
  ASSERT_TRUE(maps.init(caps, {}, error)) << error;
  ASSERT_TRUE(compositor.init(caps, {}, maps.storage(), error)) << error;
  ASSERT_TRUE(blur.init(camera.width_px, camera.height_px, ibl::CameraTransfer{}, error)) << error;
  ImageRGB8 grey;
  grey.resize(camera.width_px, camera.height_px);
  std::fill(grey.pixels.begin(), grey.pixels.end(), std::uint8_t{60});
  ASSERT_TRUE(background.upload(grey, error)) << error;
  ibl::SurfaceMaterial flat;
  flat.ambient = 1.0f;
  flat.k_diffuse = 0.0f;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = glm::vec3(0.6f);
  // The sphere is drawn one sample a pixel: its own edge has no spread, so
  // it takes the tag's whole.
  const double sigma_px = passes::objectBlurSigmaPx(tag.edge_sigma_px, 0.0);
  target.bind();
  compositor.drawCameraBackground(background);
  const int reach = static_cast<int>(radius_px) + 3;
  blur.beginObject(passes::PixelRect{static_cast<int>(centre_px.x) - reach, static_cast<int>(centre_px.y) - reach,
                                     2 * reach, 2 * reach},
                   sigma_px);
  ASSERT_TRUE(compositor.drawSphereObject(camera, pose, centre_w, radius_m, flat, lighting, maps, error)) << error;
  ASSERT_TRUE(blur.composite(nullptr, nullptr, error)) << error;
  ImageRGB8 out;
  ASSERT_TRUE(target.readRGB(out, error)) << error;

  // The silhouette's radial profile, in linear light, normalised between the
  // grey (0) and the sphere (1).
  const double outside = ibl::srgbToLinear(60.0 / 255.0), inside = 0.6;
  std::vector<std::pair<double, double>> samples;
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x) {
      const double d = radius_px - glm::length(glm::dvec2(x, y) - centre_px);  // + inside
      if (std::abs(d) > 6.0) continue;
      const double linear = ibl::srgbToLinear(out.row(y)[3 * x + 1] / 255.0);
      samples.emplace_back(d, (linear - outside) / (inside - outside));
    }
  ASSERT_GT(samples.size(), 1000u);
  const double object_spread = fittedSpreadPx(samples);
  const double tag_width = kTenToNinetyPerSigma * tag.edge_sigma_px, object_width = kTenToNinetyPerSigma * object_spread;
  std::printf("lens sigma %.1f: tag edge 10-90%% %.2f px (s %.3f), object silhouette %.2f px (s %.3f), blur added %.3f px\n",
              GetParam(), tag_width, tag.edge_sigma_px, object_width, object_spread, sigma_px);
  EXPECT_NEAR(object_width, tag_width, 0.3);

  // With the frame's noise matched too, it goes in after the blur: the
  // object's interior scatters by the noise asked, not by a blurred
  // fraction of it. The difference from the noiseless composite holds the
  // noise and both composites' rounding: sigma^2 + 2/12.
  passes::SensorNoiseMatch noise;
  noise.model.dark_code = glm::dvec3(0.0);
  noise.model.bright_code = glm::dvec3(255.0);
  noise.model.dark_sigma_code = noise.model.bright_sigma_code = glm::dvec3(2.0);
  passes::SensorNoiseTexture noise_texture;
  ASSERT_TRUE(noise_texture.init(error)) << error;
  target.bind();
  compositor.drawCameraBackground(background);
  blur.beginObject(passes::PixelRect{static_cast<int>(centre_px.x) - reach, static_cast<int>(centre_px.y) - reach,
                                     2 * reach, 2 * reach},
                   sigma_px);
  ASSERT_TRUE(compositor.drawSphereObject(camera, pose, centre_w, radius_m, flat, lighting, maps, error)) << error;
  ASSERT_TRUE(blur.composite(&noise, &noise_texture, error)) << error;
  ImageRGB8 noisy;
  ASSERT_TRUE(target.readRGB(noisy, error)) << error;
  double sum2 = 0.0;
  int interior = 0, outside_changed = 0;
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x) {
      const double r = glm::length(glm::dvec2(x, y) - centre_px);
      const double d = double(noisy.row(y)[3 * x + 1]) - double(out.row(y)[3 * x + 1]);
      if (r < 0.8 * radius_px) {
        sum2 += d * d;
        ++interior;
      } else if (r > radius_px + 4.0 * sigma_px + 2.0) {
        outside_changed += d != 0.0;
      }
    }
  const double scatter = std::sqrt(sum2 / interior);
  // ~5000 pixels: sigma's standard error is 1%.
  EXPECT_NEAR(scatter, std::sqrt(4.0 + 2.0 / 12.0), 0.15 * std::sqrt(4.0 + 2.0 / 12.0));
  EXPECT_EQ(outside_changed, 0);
}

INSTANTIATE_TEST_SUITE_P(LensBlur, BlurredObject, ::testing::Values(0.5, 1.0, 1.5));

}  // namespace
}  // namespace probelight
