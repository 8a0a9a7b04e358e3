// The object given the frame's noise (issue 19): a simulated frame with
// Gaussian noise of a known sigma, its noise measured on the tag
// (ibl::measureSensorNoise), a sphere composited over it with
// passes::ObjectCompositor adding that noise; the object's pixels then
// scatter as the frame's do, and nothing outside the object changes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <vector>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "glowing_box.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/sensor_noise.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/camera_response.hpp"
#include "passes/environment_maps.hpp"
#include "passes/model_renderer.hpp"
#include "passes/object_compositor.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "sim/tag_pattern.hpp"

namespace probelight {
namespace {

using test::GpuTest;

TEST(SensorNoiseTexels, AreStandardNormalOnceDecoded) {
  const int size = passes::SensorNoiseTexture::kSizePx;
  const std::vector<std::uint8_t> texels = passes::standardNormalTexels(size, 20081215u);
  ASSERT_EQ(texels.size(), static_cast<size_t>(size * size * 4));
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < size * size; ++i) {
      const double z = (texels[static_cast<size_t>(4 * i + c)] - 127.5) / 32.0;
      sum += z;
      sum2 += z * z;
    }
    const double n = size * size, mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
    // 16384 samples: the mean's standard error is 0.008, sigma's 0.0055;
    // the 1/32 steps add 1/(12 x 32^2) to the variance (0.004% of sigma).
    EXPECT_NEAR(mean, 0.0, 0.03) << "channel " << c;
    EXPECT_NEAR(sigma, 1.0, 0.02) << "channel " << c;
  }
  // Channels independent: their correlation is ~N(0, 1/128).
  double cross = 0.0;
  for (int i = 0; i < size * size; ++i)
    cross += (texels[static_cast<size_t>(4 * i)] - 127.5) * (texels[static_cast<size_t>(4 * i + 1)] - 127.5) / 1024.0;
  EXPECT_LT(std::abs(cross / (size * size)), 0.03);
}

TEST(SensorNoiseTexels, MoveToAnUnrelatedOffsetEachFrame) {
  std::set<std::pair<float, float>> offsets;
  for (std::uint64_t frame = 0; frame < 64; ++frame) {
    const glm::vec2 offset = passes::noiseOffsetForFrame(frame, 128);
    EXPECT_GE(offset.x, 0.0f);
    EXPECT_LT(offset.x, 1.0f);
    // Whole texels: the pattern's samples stay on texel centres.
    EXPECT_FLOAT_EQ(offset.x * 128.0f, std::round(offset.x * 128.0f));
    offsets.insert({offset.x, offset.y});
  }
  // 64 draws from 16384 offsets: a repeat has probability 12%; more than
  // two, well under 1%.
  EXPECT_GE(offsets.size(), 62u);
}

// The residual scatter about a plane over 4 x 4 patches whose pixels all
// pass `inside`, pooled (12 degrees of freedom a channel and patch).
struct PatchScatter {
  glm::dvec3 sigma_code{0.0};
  glm::dvec3 mean_code{0.0};
  int patches = 0;
};
template <typename Inside>
PatchScatter patchScatter(const ImageRGB8& image, Inside inside) {
  PatchScatter out;
  glm::dvec3 residual(0.0), mean(0.0);
  for (int y0 = 0; y0 + 4 <= image.height; y0 += 4)
    for (int x0 = 0; x0 + 4 <= image.width; x0 += 4) {
      bool all = true;
      for (int y = y0; y < y0 + 4 && all; ++y)
        for (int x = x0; x < x0 + 4 && all; ++x) all = inside(x, y);
      if (!all) continue;
      // The plane a + b dx + c dy over the symmetric grid dx, dy in
      // {-1.5, -0.5, 0.5, 1.5}: its fit is three independent sums.
      glm::dvec3 sum(0.0), sum_x(0.0), sum_y(0.0), sum2(0.0);
      for (int y = y0; y < y0 + 4; ++y)
        for (int x = x0; x < x0 + 4; ++x) {
          const std::uint8_t* p = image.row(y) + 3 * x;
          const glm::dvec3 v(p[0], p[1], p[2]);
          const double dx = x - x0 - 1.5, dy = y - y0 - 1.5;
          sum += v;
          sum_x += dx * v;
          sum_y += dy * v;
          sum2 += v * v;
        }
      // Residual = sum v^2 - (sum v)^2 / 16 - (sum dx v)^2 / sum dx^2 - (...)^2 / sum dy^2; sum dx^2 = 20.
      residual += sum2 - sum * sum / 16.0 - sum_x * sum_x / 20.0 - sum_y * sum_y / 20.0;
      mean += sum / 16.0;
      ++out.patches;
    }
  if (out.patches > 0) {
    out.sigma_code = glm::sqrt(residual / (12.0 * out.patches));
    out.mean_code = mean / static_cast<double>(out.patches);
  }
  return out;
}

class NoiseMatchedObject : public GpuTest, public ::testing::WithParamInterface<double> {};

TEST_P(NoiseMatchedObject, ScattersAsTheFrameDoesAtItsLevel) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.noise_sigma_code = GetParam();
  const sim::World world(scene);
  ImageRGB8 frame;
  FrameTruth truth;
  world.render(0, frame, truth);
  const CameraIntrinsics& camera = scene.camera;

  // The printed tag's cells, from the simulator's own bitmap of it.
  const sim::TagPattern tag(scene.rig.tag_family, scene.rig.tag_id, scene.rig.tag_size_m);
  const ibl::TagCellGrid grid = ibl::tagCellGrid(tag.borderCells(), tag.totalCells(), scene.rig.tag_size_m);
  const ibl::SensorNoiseReading reading = ibl::measureSensorNoise(
      camera, truth.pose, grid,
      [&frame](int x, int y) {
        const std::uint8_t* p = frame.row(y) + 3 * x;
        return glm::u8vec3(p[0], p[1], p[2]);
      },
      ibl::SensorNoiseSettings{});
  ASSERT_EQ(reading.status, ibl::SensorNoiseStatus::kMeasured) << reading.message;
  const passes::SensorNoiseMatch match{ibl::addedNoiseModel(reading.dark, reading.bright), 7};

  std::string error;
  const gles::Capabilities& caps = test::sharedCapabilities();
  gles::RenderTarget target;
  passes::CameraFrameTexture frame_texture;
  passes::EnvironmentMaps maps;
  passes::ObjectCompositor compositor;
  ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
  ASSERT_TRUE(frame_texture.init(caps, error)) << error;
  ASSERT_TRUE(maps.init(caps, {}, error)) << error;
  ASSERT_TRUE(compositor.init(caps, {}, maps.storage(), error)) << error;
  ASSERT_TRUE(frame_texture.upload(frame, error)) << error;

  // A flat object between the inks' levels (code 120, where the noise is
  // interpolated), standing on the tag: an ambient-lit sphere, every pixel
  // of it one value before the noise.
  ibl::SurfaceMaterial flat;
  flat.ambient = 1.0f;
  flat.k_diffuse = 0.0f;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = glm::vec3(static_cast<float>(ibl::srgbToLinear(120.0 / 255.0)));
  const glm::dvec3 centre_w(0.0, 0.0, 0.04);
  const double radius_m = 0.04;

  auto composite = [&](const passes::SensorNoiseMatch* noise) {
    compositor.setSensorNoise(noise);
    target.bind();
    compositor.drawCameraBackground(frame_texture);
    EXPECT_TRUE(compositor.drawSphereObject(camera, truth.pose, centre_w, radius_m, flat, lighting, maps, error))
        << error;
    ImageRGB8 out;
    EXPECT_TRUE(target.readRGB(out, error)) << error;
    return out;
  };
  const ImageRGB8 clean = composite(nullptr);
  const ImageRGB8 noisy = composite(&match);
  ASSERT_EQ(clean.pixels.size(), noisy.pixels.size());

  // The sphere's image: its centre's and a generous outline from the
  // projection; the interior well inside its rim.
  const glm::dvec3 centre_cam = truth.pose.toCamera(centre_w);
  const glm::dvec2 centre_px = ibl::projectToPixel(camera, centre_cam);
  const double radius_px = camera.fx_px * radius_m / centre_cam.z;
  auto distance = [&](int x, int y) { return glm::length(glm::dvec2(x, y) - centre_px); };

  // Outside the object (past its rim by 2 px: the silhouette's own pixels),
  // not one byte moved.
  int changed_outside = 0, changed_inside = 0, inside = 0;
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x) {
      const bool differs = std::memcmp(clean.row(y) + 3 * x, noisy.row(y) + 3 * x, 3) != 0;
      if (distance(x, y) > 1.2 * radius_px + 2.0) changed_outside += differs;
      if (distance(x, y) < 0.75 * radius_px) {
        ++inside;
        changed_inside += differs;
      }
    }
  EXPECT_EQ(changed_outside, 0);
  ASSERT_GT(inside, 2000) << "the sphere must cover enough pixels to measure";
  EXPECT_GT(changed_inside, inside / 3) << "noise of sigma " << GetParam() << " moves most pixels";

  const auto interior = [&](int x, int y) { return distance(x, y) < 0.75 * radius_px; };
  const PatchScatter object_clean = patchScatter(clean, interior);
  const PatchScatter object_noisy = patchScatter(noisy, interior);
  ASSERT_GT(object_noisy.patches, 100);
  // For docs/accuracy.md: the green channel's figures.
  const double frame_green = std::sqrt(std::pow(ibl::addedNoiseSigmaCode(match.model, object_clean.mean_code).y, 2) + 1.0 / 12.0);
  std::printf("noise sigma %.1f: tag black %.3f white %.3f, at the object's code %.0f %.3f; object %.3f (%+.1f%%), "
              "without the match %.3f; %d patches\n",
              GetParam(), reading.dark.sigma_code.y, reading.bright.sigma_code.y, object_clean.mean_code.y, frame_green,
              object_noisy.sigma_code.y, 100.0 * (object_noisy.sigma_code.y / frame_green - 1.0),
              object_clean.sigma_code.y, object_noisy.patches);
  for (int c = 0; c < 3; ++c) {
    // Without the match the object is flat to its rounding (0 here: one value).
    EXPECT_LT(object_clean.sigma_code[c], 0.3) << "channel " << c;
    // The frame's noise at the object's level: the two inks' noise, added
    // sigma interpolated at the object's code, with the rounding back on.
    const double added =
        ibl::addedNoiseSigmaCode(match.model, glm::dvec3(object_clean.mean_code))[c];
    const double frame_sigma = std::sqrt(added * added + 1.0 / 12.0);
    // ~150 patches x 12 degrees of freedom: sigma's standard error ~1.7%;
    // the bound is 15%.
    EXPECT_NEAR(object_noisy.sigma_code[c], frame_sigma, 0.15 * frame_sigma)
        << "channel " << c << ", frame sigma " << GetParam();
    // And against the simulator's own: its sigma, rounded to 8 bits.
    const double truth_sigma = std::sqrt(GetParam() * GetParam() + 1.0 / 12.0);
    EXPECT_NEAR(object_noisy.sigma_code[c], truth_sigma, 0.15 * truth_sigma) << "channel " << c;
    // Noise of mean zero: the object's level stays (~150 patches of 16
    // pixels: the mean's standard error is sigma / 49).
    EXPECT_NEAR(object_noisy.mean_code[c], object_clean.mean_code[c], 0.15 + 0.1 * GetParam()) << "channel " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(NoiseSettings, NoiseMatchedObject, ::testing::Values(0.8, 1.5, 3.0));

// A glTF model given the noise: in its own shader when drawn straight into
// the frame, at the resolve of the supersampled edge layer otherwise (the
// 2 x 2 and 4 x 4 grids' box filter would divide a per-sub-sample noise's
// sigma by 2 and 4). A flat glowing box over a uniform background, with a
// noise model given by hand: sigma 1 code at code 40, 3 at code 200.
class NoiseMatchedModel : public GpuTest, public ::testing::WithParamInterface<int> {};

TEST_P(NoiseMatchedModel, ScattersAsTheNoiseModelSaysWhateverTheEdgeStrategy) {
  const int edge_samples = GetParam();
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(test::initBlackMaps(maps, caps, error)) << error;
  const CameraIntrinsics camera = test::testCamera();
  const PoseCamFromWorld pose = test::lookAt({0.09, -0.25, 0.19}, {0.0, 0.0, 0.03});
  // Code 120 in sRGB: where the noise model gives sigma 2.
  const model::MeshModel box = test::glowingBox(glm::vec3(static_cast<float>(ibl::srgbToLinear(120.0 / 255.0))));
  passes::SensorNoiseMatch match;
  match.model.dark_code = glm::dvec3(40.0);
  match.model.bright_code = glm::dvec3(200.0);
  match.model.dark_sigma_code = glm::dvec3(1.0);
  match.model.bright_sigma_code = glm::dvec3(3.0);
  match.frame_index = 3;

  gles::RenderTarget target;
  ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
  passes::ModelRenderer renderer;
  passes::ModelRendererSettings settings;
  settings.edge_samples = edge_samples;
  ASSERT_TRUE(renderer.init(caps, maps.storage(), box, test::glowingBoxPlacement(), settings, error)) << error;
  auto render = [&](const passes::SensorNoiseMatch* noise) {
    renderer.setSensorNoise(noise);
    target.bind();
    glClearColor(40.0f / 255.0f, 40.0f / 255.0f, 40.0f / 255.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    EXPECT_TRUE(renderer.draw(camera, pose, ibl::SceneLighting{}, maps, error)) << error;
    ImageRGB8 out;
    EXPECT_TRUE(target.readRGB(out, error)) << error;
    return out;
  };
  const ImageRGB8 clean = render(nullptr);
  const ImageRGB8 noisy = render(&match);
  const std::uint8_t* centre = clean.row(clean.height / 2) + 3 * (clean.width / 2);
  auto isBox = [&](int x, int y) {
    const std::uint8_t* p = clean.row(y) + 3 * x;
    return std::memcmp(p, centre, 3) == 0;
  };
  ASSERT_NE(centre[1], 40) << "the box must cover the frame's centre";
  int background = 0, background_changed = 0;
  for (int y = 1; y + 1 < camera.height_px; ++y)
    for (int x = 1; x + 1 < camera.width_px; ++x) {
      bool clear = true;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) clear = clear && clean.row(y + dy)[3 * (x + dx) + 1] == 40;
      if (!clear) continue;
      ++background;
      background_changed += std::memcmp(clean.row(y) + 3 * x, noisy.row(y) + 3 * x, 3) != 0;
    }
  EXPECT_GT(background, 100000);
  EXPECT_EQ(background_changed, 0);

  const PatchScatter flat = patchScatter(clean, isBox);
  const PatchScatter grain = patchScatter(noisy, isBox);
  ASSERT_GT(grain.patches, 200);
  std::printf("model, %d edge samples (%s): box code %.0f, sigma %.3f (noise model %.3f with the rounding)\n",
              edge_samples, passes::edgeStrategyName(renderer.stats().edges.strategy), flat.mean_code.y,
              grain.sigma_code.y,
              std::sqrt(std::pow(ibl::addedNoiseSigmaCode(match.model, flat.mean_code).y, 2) + 1.0 / 12.0));
  for (int c = 0; c < 3; ++c) {
    EXPECT_LT(flat.sigma_code[c], 0.3) << "channel " << c;
    const double added = ibl::addedNoiseSigmaCode(match.model, flat.mean_code)[c];
    const double expected = std::sqrt(added * added + 1.0 / 12.0);
    EXPECT_NEAR(grain.sigma_code[c], expected, 0.15 * expected) << "channel " << c;
    EXPECT_NEAR(grain.mean_code[c], flat.mean_code[c], 0.3) << "channel " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(EdgeSamples, NoiseMatchedModel, ::testing::Values(1, 4, 16));

}  // namespace
}  // namespace probelight
