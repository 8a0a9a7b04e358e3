// The lens's glare around the object's light above white (passes/
// object_bloom): a flat sphere at 1.5 x white over a dark uniform frame.
// The clip keeps 1 of it; the bloom spreads the other 0.5 by the glare's
// Gaussian, so the light added outside the sphere is what that Gaussian
// puts there: the CPU's convolution of the sphere's own pixels (as drawn
// without the bloom) with the same Gaussian.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "glowing_box.hpp"
#include "ibl/color_transfer.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/object_bloom.hpp"
#include "passes/object_blur.hpp"
#include "passes/model_renderer.hpp"
#include "passes/object_compositor.hpp"

namespace probelight {
namespace {

using test::GpuTest;

TEST(ObjectBloom, TheLayerIsCoarserForAWiderGlare) {
  // 3 sigma within the taps at the layer's resolution, never finer than half.
  EXPECT_EQ(passes::bloomDownsampleFor(1.0), 2);
  EXPECT_EQ(passes::bloomDownsampleFor(4.4), 2);
  EXPECT_EQ(passes::bloomDownsampleFor(17.0), 5);
  for (double sigma : {3.0, 9.0, 30.0})
    EXPECT_LE(3.0 * sigma / passes::bloomDownsampleFor(sigma), passes::kMaxObjectBlurTaps) << sigma;
}

struct BloomScene {
  CameraIntrinsics camera = test::testCamera();
  PoseCamFromWorld pose = test::lookAt({0.0, -0.30, 0.20}, {0.0, 0.0, 0.03});
  glm::dvec3 centre{0.0, 0.0, 0.03};
  double radius_m = 0.03;
};

// The frame at `base_linear` everywhere, the flat sphere at `light`, then
// (with bloom) its light beyond white spread by sigma_px.
ImageRGB8 render(const BloomScene& scene, float light, double base_linear, passes::ObjectBloom* bloom) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  ImageRGB8 result;
  passes::EnvironmentMaps maps;
  EXPECT_TRUE(test::initBlackMaps(maps, caps, error)) << error;
  gles::RenderTarget target;
  EXPECT_TRUE(target.init(scene.camera.width_px, scene.camera.height_px, error)) << error;
  passes::CameraFrameTexture frame;
  EXPECT_TRUE(frame.init(caps, error)) << error;
  ImageRGB8 base;
  base.resize(scene.camera.width_px, scene.camera.height_px);
  std::fill(base.pixels.begin(), base.pixels.end(),
            static_cast<std::uint8_t>(std::lround(255.0 * ibl::linearToSrgb(base_linear))));
  EXPECT_TRUE(frame.upload(base, error)) << error;
  passes::ObjectCompositor compositor;
  EXPECT_TRUE(compositor.init(caps, {}, maps.storage(), error)) << error;
  ibl::SurfaceMaterial flat;
  flat.ambient = 1.0f;
  flat.k_diffuse = 0.0f;
  flat.k_specular = 0.0f;
  flat.k_reflect = 0.0f;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = glm::vec3(light);
  target.bind();
  compositor.drawCameraBackground(frame);
  EXPECT_TRUE(compositor.drawSphereObject(scene.camera, scene.pose, scene.centre, scene.radius_m, flat, lighting,
                                          maps, error))
      << error;
  if (bloom != nullptr) {
    const passes::PixelRect region =
        passes::projectedBounds(scene.camera, scene.pose, scene.centre - glm::dvec3(scene.radius_m),
                                scene.centre + glm::dvec3(scene.radius_m), 0.01, 2);
    bloom->beginBrightPass(region);
    compositor.setBloomBrightPass(true);
    EXPECT_TRUE(compositor.drawSphereObject(scene.camera, scene.pose, scene.centre, scene.radius_m, flat, lighting,
                                            maps, error))
        << error;
    compositor.setBloomBrightPass(false);
    EXPECT_TRUE(bloom->composite(error)) << error;
  }
  EXPECT_TRUE(target.readRGB(result, error)) << error;
  return result;
}

double linearOf(std::uint8_t code) { return ibl::srgbToLinear(code / 255.0); }

// The light `bloomed` adds outside the object's white pixels in `plain`
// (green, linear), against the CPU's spread of `beyond_white` on each of
// them by the Gaussian of sigma_px (sampled at whole pixels, normalised,
// 5 sigma, rows then columns). Nothing may change beyond its reach.
void expectSpreadAsTheGaussian(const ImageRGB8& plain, const ImageRGB8& bloomed, double beyond_white,
                               double sigma_px, int downsample, const char* what) {
  const int width = plain.width, height = plain.height;
  std::vector<double> beyond(static_cast<size_t>(width) * height, 0.0);
  int object_pixels = 0;
  for (int i = 0; i < width * height; ++i)
    if (plain.pixels[3 * i + 1] == 255) {
      beyond[static_cast<size_t>(i)] = beyond_white;
      ++object_pixels;
    }
  ASSERT_GT(object_pixels, 2000) << what;
  const int reach = static_cast<int>(std::ceil(5.0 * sigma_px));
  std::vector<double> kernel(static_cast<size_t>(2 * reach + 1));
  double kernel_sum = 0.0;
  for (int k = -reach; k <= reach; ++k)
    kernel_sum += kernel[static_cast<size_t>(k + reach)] = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
  for (double& w : kernel) w /= kernel_sum;
  std::vector<double> rows(beyond.size(), 0.0), spread(beyond.size(), 0.0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int k = -reach; k <= reach; ++k)
        if (x + k >= 0 && x + k < width)
          rows[static_cast<size_t>(y) * width + x] +=
              kernel[static_cast<size_t>(k + reach)] * beyond[static_cast<size_t>(y) * width + x + k];
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int k = -reach; k <= reach; ++k)
        if (y + k >= 0 && y + k < height)
          spread[static_cast<size_t>(y) * width + x] +=
              kernel[static_cast<size_t>(k + reach)] * rows[static_cast<size_t>(y + k) * width + x];
  double added = 0.0, expected = 0.0;
  int changed_far = 0, object_dimmed = 0;
  for (size_t i = 0; i < beyond.size(); ++i) {
    if (beyond[i] > 0.0) {
      object_dimmed += bloomed.pixels[3 * i + 1] != 255 ? 1 : 0;  // the object stays white
      continue;
    }
    added += linearOf(bloomed.pixels[3 * i + 1]) - linearOf(plain.pixels[3 * i + 1]);
    expected += spread[i];
    if (spread[i] < 1e-6 && bloomed.pixels[3 * i + 1] != plain.pixels[3 * i + 1]) ++changed_far;
  }
  std::cout << what << ": sigma " << sigma_px << " px (layer 1/" << downsample << "), light added outside "
            << added << " against " << expected << " (" << 100.0 * (added / expected - 1.0) << "%), of "
            << beyond_white * object_pixels << " beyond white\n";
  // The layer samples the object at 1/downsample of the resolution: its
  // outline moves by up to half a layer texel, either way round the rim
  // (so it mostly cancels), and the 8-bit layer's steps near the halo's
  // faint tail are BLOOM_RANGE / 255^2 of white. 10% holds both.
  EXPECT_NEAR(added / expected, 1.0, 0.10) << what;
  EXPECT_EQ(changed_far, 0) << what;
  EXPECT_EQ(object_dimmed, 0) << what;
}

// 0.5 and 2 degrees of field at fx 530: 4.6 px (a layer at 1/2) and 18.5 px (1/5).
class BloomSpread : public GpuTest, public ::testing::WithParamInterface<double> {};

TEST_P(BloomSpread, TheLightBeyondWhiteIsSpreadByTheGlaresGaussian) {
  const BloomScene scene;
  const double sigma_px = scene.camera.fx_px * std::tan(GetParam() * M_PI / 180.0);
  constexpr double kBase = 0.02, kLight = 1.5;
  std::string error;
  passes::ObjectBloom bloom;
  ASSERT_TRUE(bloom.init(scene.camera.width_px, scene.camera.height_px, sigma_px, {}, error)) << error;
  const ImageRGB8 plain = render(scene, static_cast<float>(kLight), kBase, nullptr);
  const ImageRGB8 bloomed = render(scene, static_cast<float>(kLight), kBase, &bloom);
  expectSpreadAsTheGaussian(plain, bloomed, kLight - 1.0, sigma_px, bloom.downsample(), "sphere");
}

// A glTF model's emissive part at twice white (a glowing box): its bright
// pass is drawn straight into the layer, whatever its edges would use.
TEST_F(GpuTest, AModelsGlowBeyondWhiteBlooms) {
  const CameraIntrinsics camera = test::testCamera();
  const PoseCamFromWorld pose = test::lookAt({0.09, -0.25, 0.19}, {0.0, 0.0, 0.03});
  const double sigma_px = 4.6;
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(test::initBlackMaps(maps, caps, error)) << error;
  gles::RenderTarget target;
  ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
  passes::ModelRenderer renderer;
  ASSERT_TRUE(renderer.init(caps, maps.storage(), test::glowingBox(glm::vec3(2.0f)), test::glowingBoxPlacement(), {},
                            error))
      << error;
  passes::ObjectBloom bloom;
  ASSERT_TRUE(bloom.init(camera.width_px, camera.height_px, sigma_px, {}, error)) << error;
  auto draw = [&](bool with_bloom) {
    ImageRGB8 result;
    target.bind();
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    EXPECT_TRUE(renderer.draw(camera, pose, ibl::SceneLighting{}, maps, error)) << error;
    if (with_bloom) {
      bloom.beginBrightPass(passes::PixelRect{0, 0, camera.width_px, camera.height_px});
      renderer.setBloomBrightPass(true);
      EXPECT_TRUE(renderer.draw(camera, pose, ibl::SceneLighting{}, maps, error)) << error;
      renderer.setBloomBrightPass(false);
      EXPECT_TRUE(bloom.composite(error)) << error;
    }
    EXPECT_TRUE(target.readRGB(result, error)) << error;
    return result;
  };
  const ImageRGB8 plain = draw(false);
  const ImageRGB8 bloomed = draw(true);
  expectSpreadAsTheGaussian(plain, bloomed, 1.0, sigma_px, bloom.downsample(), "model");
}

INSTANTIATE_TEST_SUITE_P(GlareDegrees, BloomSpread, ::testing::Values(0.5, 2.0));

// A sphere below white has nothing beyond it: the pass adds nothing (the
// decode and encode of the frame under the region give back its bytes).
TEST_F(GpuTest, AnObjectBelowWhiteGetsNoBloom) {
  const BloomScene scene;
  std::string error;
  passes::ObjectBloom bloom;
  ASSERT_TRUE(bloom.init(scene.camera.width_px, scene.camera.height_px, 4.6, {}, error)) << error;
  const ImageRGB8 plain = render(scene, 0.9f, 0.2, nullptr);
  const ImageRGB8 bloomed = render(scene, 0.9f, 0.2, &bloom);
  int differing = 0;
  for (size_t i = 0; i < plain.pixels.size(); ++i) differing += plain.pixels[i] != bloomed.pixels[i] ? 1 : 0;
  EXPECT_EQ(differing, 0);
}

}  // namespace
}  // namespace probelight
