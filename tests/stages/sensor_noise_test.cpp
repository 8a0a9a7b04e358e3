// The frame's noise measured on the tag's cells, against the simulator,
// which adds Gaussian noise of a known sigma (in code values, after the
// sRGB encoding) and then rounds to 8 bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ibl/sensor_noise.hpp"
#include "sim/camera_path.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "stages/stage_settings.hpp"

namespace probelight {
namespace {

struct RenderedFrame {
  ImageRGB8 image;
  FrameTruth truth;
};

RenderedFrame render(const sim::SceneConfig& scene) {
  const sim::World world(scene);
  RenderedFrame frame;
  world.render(0, frame.image, frame.truth);
  return frame;
}

ibl::RgbPixelReader readerOf(const ImageRGB8& image) {
  return [&image](int x, int y) {
    const std::uint8_t* p = image.row(y) + 3 * x;
    return glm::u8vec3(p[0], p[1], p[2]);
  };
}

ibl::TagCellGrid gridOf(const sim::SceneConfig& scene) {
  const std::optional<ibl::TagCellGrid> grid = tagCellGridOf(scene.rig);
  EXPECT_TRUE(grid);
  return grid.value_or(ibl::TagCellGrid{});
}

// The estimate pools about 40 cells of ~30 interior pixels a level (~1100
// degrees of freedom): a sigma's standard error is 1/sqrt(2 x 1100) = 2%
// a channel and level, so 10% is five standard errors; a bias the cell
// edges, the light's gradient or the rounding left in would show above it.
constexpr double kSigmaTolerance = 0.10;

class SensorNoiseAtSetting : public ::testing::TestWithParam<double> {};

TEST_P(SensorNoiseAtSetting, AddedNoiseIsTheSimulatorsSigmaAtBothInks) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.noise_sigma_code = GetParam();
  const RenderedFrame frame = render(scene);
  const ibl::SensorNoiseReading reading = ibl::measureSensorNoise(
      scene.camera, frame.truth.pose, gridOf(scene), readerOf(frame.image), ibl::SensorNoiseSettings{});
  ASSERT_EQ(reading.status, ibl::SensorNoiseStatus::kMeasured) << reading.message;
  // Black ink (albedo 0.04) and white (0.85) under the same light.
  EXPECT_LT(reading.dark.mean_code.y + 60.0, reading.bright.mean_code.y);
  EXPECT_GE(reading.dark.cells, 20);
  EXPECT_GE(reading.bright.cells, 20);
  const ibl::AddedNoiseModel model = ibl::addedNoiseModel(reading.dark, reading.bright);
  // For docs/accuracy.md.
  std::printf("sim sigma %.1f: added sigma black (%.3f %.3f %.3f) at code %.0f, white (%.3f %.3f %.3f) at code %.0f; "
              "%d + %d cells, %ld + %ld pixels\n",
              scene.noise_sigma_code, model.dark_sigma_code.x, model.dark_sigma_code.y, model.dark_sigma_code.z,
              reading.dark.mean_code.y, model.bright_sigma_code.x, model.bright_sigma_code.y,
              model.bright_sigma_code.z, reading.bright.mean_code.y, reading.dark.cells, reading.bright.cells,
              reading.dark.pixels, reading.bright.pixels);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(model.dark_sigma_code[c], scene.noise_sigma_code, kSigmaTolerance * scene.noise_sigma_code)
        << "channel " << c << ", black cells";
    EXPECT_NEAR(model.bright_sigma_code[c], scene.noise_sigma_code, kSigmaTolerance * scene.noise_sigma_code)
        << "channel " << c << ", white cells";
    // What the frame shows holds its own rounding as well.
    EXPECT_GT(reading.bright.sigma_code[c], model.bright_sigma_code[c]);
  }
}

INSTANTIATE_TEST_SUITE_P(NoiseSettings, SensorNoiseAtSetting, ::testing::Values(0.8, 1.5, 3.0));

TEST(SensorNoise, CellsAnEdgeCrossesAreLeftOut) {
  // A patch of extra light with a sharp edge (a lamp's spot) across the
  // tag: the cells it crosses are not flat; the rest measure the noise as
  // before, since adding a constant changes no pixel's noise.
  sim::SceneConfig scene = sim::defaultScene();
  scene.noise_sigma_code = 1.5;
  RenderedFrame frame = render(scene);
  const ibl::SensorNoiseReading clean = ibl::measureSensorNoise(
      scene.camera, frame.truth.pose, gridOf(scene), readerOf(frame.image), ibl::SensorNoiseSettings{});
  ASSERT_EQ(clean.status, ibl::SensorNoiseStatus::kMeasured) << clean.message;
  const glm::dvec3 tag_centre_cam = frame.truth.pose.toCamera(glm::dvec3(0.0));
  const glm::dvec2 tag_centre_px(scene.camera.fx_px * tag_centre_cam.x / tag_centre_cam.z + scene.camera.cx_px,
                                  scene.camera.fy_px * tag_centre_cam.y / tag_centre_cam.z + scene.camera.cy_px);
  // A slanted edge: it crosses the cells' rows and columns both.
  for (int y = 0; y < frame.image.height; ++y)
    for (int x = 0; x < frame.image.width; ++x)
      for (int c = 0; c < 3; ++c) {
        if ((x - tag_centre_px.x) + 0.6 * (y - tag_centre_px.y) < 3.0) continue;
        std::uint8_t& code = frame.image.row(y)[3 * x + c];
        code = static_cast<std::uint8_t>(std::min(255, code + 40));
      }
  const ibl::SensorNoiseReading lit = ibl::measureSensorNoise(
      scene.camera, frame.truth.pose, gridOf(scene), readerOf(frame.image), ibl::SensorNoiseSettings{});
  ASSERT_EQ(lit.status, ibl::SensorNoiseStatus::kMeasured) << lit.message;
  // The edge crosses five of the cells' interiors (the rest it passes
  // in their 2 px margins).
  EXPECT_GE(lit.cells_left_out, clean.cells_left_out + 3);
  // Kept, those cells would have spoiled the estimate.
  ibl::SensorNoiseSettings keep_all;
  keep_all.outlier_variance_ratio = 1e9;
  const ibl::SensorNoiseReading spoiled = ibl::measureSensorNoise(
      scene.camera, frame.truth.pose, gridOf(scene), readerOf(frame.image), keep_all);
  EXPECT_GT(std::max(spoiled.dark.sigma_code.y, spoiled.bright.sigma_code.y), 1.5 * 1.5);
  const ibl::AddedNoiseModel model = ibl::addedNoiseModel(lit.dark, lit.bright);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(model.dark_sigma_code[c], 1.5, kSigmaTolerance * 1.5) << "channel " << c;
    EXPECT_NEAR(model.bright_sigma_code[c], 1.5, kSigmaTolerance * 1.5) << "channel " << c;
  }
}

TEST(SensorNoise, ATagTooSmallInTheImageIsSaidSo) {
  // At 3 m a 12.5 mm cell is 2.5 px: no pixel 2 px from its edges.
  sim::SceneConfig scene = sim::defaultScene();
  scene.camera_path.distance_m = 3.0;
  const RenderedFrame frame = render(scene);
  const ibl::SensorNoiseReading reading = ibl::measureSensorNoise(
      scene.camera, frame.truth.pose, gridOf(scene), readerOf(frame.image), ibl::SensorNoiseSettings{});
  EXPECT_EQ(reading.status, ibl::SensorNoiseStatus::kTooSmall);
  EXPECT_GT(reading.cells_in_view, 0);
  EXPECT_NE(reading.message.find("too small"), std::string::npos) << reading.message;
}

TEST(SensorNoise, ATagOutOfViewIsSaidSo) {
  const sim::SceneConfig scene = sim::defaultScene();
  // Looking level, away from the tag: it is behind the camera.
  const PoseCamFromWorld away = sim::lookAtPose(glm::dvec3(0.0, -0.5, 0.3), glm::dvec3(0.0, -5.0, 0.3));
  const ImageRGB8 grey = [&] {
    ImageRGB8 image;
    image.resize(scene.camera.width_px, scene.camera.height_px);
    return image;
  }();
  const ibl::SensorNoiseReading reading =
      ibl::measureSensorNoise(scene.camera, away, gridOf(scene), readerOf(grey), ibl::SensorNoiseSettings{});
  EXPECT_EQ(reading.status, ibl::SensorNoiseStatus::kNotInView);
  EXPECT_EQ(reading.cells_in_view, 0);
}

TEST(SensorNoise, AFlatGreyCardHasNoTwoInks) {
  // The tag's pose over a uniform grey with no noise: every cell is flat,
  // but there is one level, not two.
  sim::SceneConfig scene = sim::defaultScene();
  const RenderedFrame frame = render(scene);
  ImageRGB8 grey;
  grey.resize(scene.camera.width_px, scene.camera.height_px);
  std::fill(grey.pixels.begin(), grey.pixels.end(), std::uint8_t{120});
  const ibl::SensorNoiseReading reading = ibl::measureSensorNoise(
      scene.camera, frame.truth.pose, gridOf(scene), readerOf(grey), ibl::SensorNoiseSettings{});
  EXPECT_EQ(reading.status, ibl::SensorNoiseStatus::kNotFlat) << reading.message;
}

TEST(AddedNoiseModel, LinearBetweenTheInksConstantBeyondLessTheFramesRounding) {
  ibl::NoiseAtLevel dark, bright;
  dark.mean_code = glm::dvec3(40.0);
  bright.mean_code = glm::dvec3(200.0);
  // sqrt(s^2 + 1/12): the frame's rounding on top of an added s.
  dark.sigma_code = glm::sqrt(glm::dvec3(1.0 + 1.0 / 12.0));
  bright.sigma_code = glm::sqrt(glm::dvec3(9.0 + 1.0 / 12.0));
  const ibl::AddedNoiseModel model = ibl::addedNoiseModel(dark, bright);
  EXPECT_NEAR(ibl::addedNoiseSigmaCode(model, glm::dvec3(40.0)).x, 1.0, 1e-12);
  EXPECT_NEAR(ibl::addedNoiseSigmaCode(model, glm::dvec3(120.0)).y, 2.0, 1e-12);
  EXPECT_NEAR(ibl::addedNoiseSigmaCode(model, glm::dvec3(200.0)).z, 3.0, 1e-12);
  EXPECT_NEAR(ibl::addedNoiseSigmaCode(model, glm::dvec3(5.0)).x, 1.0, 1e-12);
  EXPECT_NEAR(ibl::addedNoiseSigmaCode(model, glm::dvec3(250.0)).x, 3.0, 1e-12);
  // A frame no noisier than its own rounding gets none added.
  dark.sigma_code = glm::dvec3(0.2);
  EXPECT_EQ(ibl::addedNoiseModel(dark, bright).dark_sigma_code, glm::dvec3(0.0));
}

}  // namespace
}  // namespace probelight
