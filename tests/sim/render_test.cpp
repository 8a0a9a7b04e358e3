// The camera model of rendered frames: exposure, shading, determinism, noise.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

TEST(Render, WhiteTagBorderReadsHalfLinearUnderAutoExposure) {
  SceneConfig scene = defaultScene();
  scene.noise_sigma_code = 0.0;
  scene.camera_path.name = "static";
  World world(scene);
  ImageRGB8 image;
  FrameTruth truth;
  world.render(0, image, truth);
  // Middle of the white ring above the tag's top edge (8 + 1 cells of 12.5 mm).
  auto p = projectWorldPoints(scene.camera, truth.pose, {{0.0, 0.05 + 0.00625, 0.0}});
  int x = static_cast<int>(std::lround(p[0].x)), y = static_cast<int>(std::lround(p[0].y));
  // Luminance of the white patch: auto exposure targets 0.5 on the Rec.709 Y
  // of E_up. One 8-bit code near 0.5 linear is 0.004; sRGB tabulation adds
  // < 0.002 codes: 0.006 covers rounding of all three channels.
  double y_linear = 0.2126 * testing::pixelLinear(image, x, y, 0) + 0.7152 * testing::pixelLinear(image, x, y, 1) +
                    0.0722 * testing::pixelLinear(image, x, y, 2);
  EXPECT_NEAR(y_linear, 0.5, 0.006);
  EXPECT_NEAR(truth.exposure, world.exposure(), 0.0);
}

TEST(Render, BallShowsReflectanceTimesUniformSky) {
  SceneConfig scene = testing::smallScene();
  scene.environment = "uniform";
  scene.floor_albedo = scene.tag_black_albedo = scene.tag_white_albedo = 1.0;
  scene.floor_texture_contrast = 0.0;
  scene.noise_sigma_code = 0.0;
  scene.rig.probe_reflectance = 0.6;
  scene.camera_path.name = "static";
  World world(scene);
  ImageRGB8 image;
  FrameTruth truth;
  world.render(0, image, truth);
  std::vector<float> ball = world.coverage(0, SceneObject::kProbe);
  // Everything the ball can see has radiance 1, so every fully covered ball
  // pixel is 0.6 * exposure (~0.35 linear); one code there is ~0.003.
  int checked = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (ball[y * image.width + x] == 1.0f) {
        ++checked;
        EXPECT_NEAR(testing::pixelLinear(image, x, y, 1), 0.6 * world.exposure(), 0.004);
      }
  EXPECT_GT(checked, 20);
}

TEST(Render, SameFrameIndexGivesIdenticalBytesWhateverTheOrder) {
  SceneConfig scene = testing::smallScene();
  World first(scene), second(scene);
  ImageRGB8 a, b, other;
  FrameTruth truth;
  first.render(7, a, truth);
  first.render(3, other, truth);
  second.render(11, other, truth);
  second.render(7, b, truth);
  EXPECT_EQ(a.pixels, b.pixels);
  first.render(8, other, truth);
  EXPECT_NE(a.pixels, other.pixels);
}

TEST(Render, NoiseHasRequestedSigmaAndNoMean) {
  SceneConfig noisy = defaultScene();
  noisy.camera_path.name = "static";
  noisy.noise_sigma_code = 1.5;
  SceneConfig clean = noisy;
  clean.noise_sigma_code = 0.0;
  World noisy_world(noisy), clean_world(clean);
  ImageRGB8 with_noise, without_noise;
  FrameTruth truth;
  noisy_world.render(0, with_noise, truth);
  clean_world.render(0, without_noise, truth);
  double sum = 0, sum_sq = 0;
  long count = 0;
  for (size_t i = 0; i < with_noise.pixels.size(); ++i) {
    int code = without_noise.pixels[i];
    if (code < 8 || code > 247) continue;  // away from the clip at 0 and 255
    double diff = double(with_noise.pixels[i]) - code;
    sum += diff;
    sum_sq += diff * diff;
    ++count;
  }
  ASSERT_GT(count, 500000);
  double mean = sum / count;
  double sigma = std::sqrt(sum_sq / count - mean * mean);
  // round(v + n) - round(v) has variance sigma^2 plus up to 1/4 from rounding
  // (1/12 on average): sigma in [1.5, 1.58]. With ~9e5 samples the estimate
  // itself is good to 0.1%.
  EXPECT_GT(sigma, 1.47);
  EXPECT_LT(sigma, 1.60);
  // The rounding offsets v - round(v) average ~0 over many different v; the
  // standard error is 1.5 / sqrt(9e5) = 0.002.
  EXPECT_NEAR(mean, 0.0, 0.03);
}

TEST(Render, NoiseIsIndependentBetweenNeighboursAndFrames) {
  // A static camera under static light: frames 0 and 1 differ only by noise.
  // Their difference has zero mean given the clean value (both frames round
  // the same v), so any correlation left would come from the generator.
  SceneConfig scene = defaultScene();
  scene.camera_path.name = "static";
  World world(scene);
  ImageRGB8 frame0, frame1;
  FrameTruth truth;
  world.render(0, frame0, truth);
  world.render(1, frame1, truth);
  const int w = frame0.width;
  std::vector<double> diff(frame0.pixels.size());
  for (size_t i = 0; i < diff.size(); ++i) diff[i] = double(frame0.pixels[i]) - double(frame1.pixels[i]);
  double sum_sq = 0, sum_right = 0, sum_below = 0, sum_channel = 0;
  long count = 0;
  for (size_t i = 0; i + 3 * w < diff.size(); ++i) {
    if (frame0.pixels[i] < 8 || frame0.pixels[i] > 247 || (i / 3) % w == static_cast<size_t>(w - 1)) continue;
    sum_sq += diff[i] * diff[i];
    sum_right += diff[i] * diff[i + 3];
    sum_below += diff[i] * diff[i + 3 * w];
    if (i % 3 != 2) sum_channel += diff[i] * diff[i + 1];
    ++count;
  }
  // Var(d) = 2 (sigma^2 + ~1/12): sigma_frame = sqrt(Var/2) in [1.5, 1.58].
  double sigma_frame = std::sqrt(sum_sq / count / 2.0);
  EXPECT_GT(sigma_frame, 1.47);
  EXPECT_LT(sigma_frame, 1.60);
  // Independent samples: correlations ~ 0 +- 1/sqrt(9e5) = 0.001.
  EXPECT_NEAR(sum_right / sum_sq, 0.0, 0.01);
  EXPECT_NEAR(sum_below / sum_sq, 0.0, 0.01);
  EXPECT_NEAR(sum_channel / sum_sq, 0.0, 0.01);
}

TEST(Render, DifferentSeedsGiveDifferentNoise) {
  SceneConfig a = testing::smallScene();
  a.camera_path.name = "static";
  SceneConfig b = a;
  b.seed = a.seed + 1;
  World world_a(a), world_b(b);
  ImageRGB8 image_a, image_b;
  FrameTruth truth;
  world_a.render(0, image_a, truth);
  world_b.render(0, image_b, truth);
  EXPECT_NE(image_a.pixels, image_b.pixels);
}

TEST(RandomPoses, KeepTagAndBallInViewAcrossGrazingAndFrontoViews) {
  SceneConfig scene = defaultScene();
  scene.camera_path.name = "random";
  World world(scene);
  int grazing = 0, fronto = 0;
  for (std::uint64_t frame = 0; frame < 90; ++frame) {
    FrameTruth truth = world.truth(frame);
    EXPECT_TRUE(truth.tag_fully_visible) << frame;
    EXPECT_TRUE(truth.probe_fully_visible) << frame;
    EXPECT_GT(truth.probe_radius_px, 15.0) << frame;
    // Elevation of the viewing direction above the ground plane.
    glm::dvec3 forward_w = glm::transpose(truth.pose.R_cam_from_world) * glm::dvec3(0, 0, 1);
    double elevation_deg = std::asin(-forward_w.z) * 180.0 / std::numbers::pi;
    if (elevation_deg < 27.0) ++grazing;
    if (elevation_deg > 75.0) ++fronto;
  }
  EXPECT_GE(grazing, 20);
  EXPECT_GE(fronto, 20);
}

TEST(DefaultScene, BallIsAtLeast25PixelsAcrossTheFirstOrbitQuarter) {
  World world(defaultScene());
  for (std::uint64_t frame = 0; frame <= 450; frame += 50) {
    FrameTruth truth = world.truth(frame);
    EXPECT_TRUE(truth.tag_fully_visible) << frame;
    EXPECT_TRUE(truth.probe_fully_visible) << frame;
    EXPECT_GE(truth.probe_radius_px, 25.0) << frame;
  }
}

}  // namespace
}  // namespace probelight::sim
