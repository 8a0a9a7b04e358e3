// The brute-force irradiance against closed forms, and the relations between
// its hdr and clipped variants.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/math_constants.hpp"
#include "sim/environment.hpp"
#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

TEST(IrradianceTruth, UniformWhiteWorldGivesPiLInEveryDirection) {
  // Uniform sky L = 1 over a ground of albedo 1 with no texture: the ground
  // radiance is albedo * E_up / pi = 1, so the whole sphere is L = 1 and every
  // normal receives pi * L.
  SceneConfig scene = testing::smallScene();
  scene.environment = "uniform";
  scene.floor_albedo = scene.tag_black_albedo = scene.tag_white_albedo = 1.0;
  scene.floor_texture_contrast = 0.0;
  World world(scene);
  // Auto exposure: white 0.85 under E_up = pi reads 0.5.
  EXPECT_NEAR(world.exposure(), 0.5 / 0.85, 1e-9);
  for (glm::dvec3 normal : {glm::dvec3{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0.3, -0.5, 0.8}, {-0.6, 0.2, -0.7}}) {
    IrradianceTruth e = world.irradiance(glm::normalize(normal), 0);
    // Exact cell moments make cells wholly above n's horizon exact; cells cut
    // by the horizon (~800 of them, each 1.5e-4 sr across 0.012 rad) can lose
    // at most ~1e-3 absolute in total: 1e-3 relative is a safe bound.
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(e.hdr[c], kPi * world.exposure(), 1e-3 * kPi * world.exposure());
      // 0.59 < 1: nothing clips, so both variants agree.
      EXPECT_NEAR(e.clipped[c], e.hdr[c], 1e-9);
    }
  }
}

TEST(IrradianceTruth, CieOvercastSkyOnUpwardNormalMatchesClosedForm) {
  // L(theta) = Lz (1 + 2 cos theta) / 3 gives
  // E_up = 2 pi Lz / 3 * integral_0^{pi/2} (1 + 2 cos) cos sin d theta = 7 pi Lz / 9.
  SceneConfig scene = testing::smallScene();
  scene.environment = "overcast";
  World world(scene);
  const double zenith_radiance = makeEnvironment("overcast")->radiance({0, 0, 1}).g;
  const double expected = 7.0 * kPi / 9.0 * zenith_radiance;
  // The smooth sky is integrated by a 3x3 midpoint rule per 0.7 deg cell:
  // error O(h^2) ~ 1e-5; 1e-4 relative is generous.
  EXPECT_NEAR(world.groundIrradianceUp(0).g, expected, 1e-4 * expected);
  IrradianceTruth up = world.irradiance({0, 0, 1}, 0);
  EXPECT_NEAR(up.hdr.g, expected * world.exposure(), 1e-4 * expected * world.exposure());
}

TEST(IrradianceTruth, ClippedNeverExceedsHdrAndLosesTheSun) {
  SceneConfig scene = testing::smallScene();  // sun_sky
  scene.rig.probe_reflectance = 0.7;
  World world(scene);
  double largest_loss = 0.0;
  for (int i = 0; i < 40; ++i) {
    // Spread normals over the sphere (golden-angle spiral).
    double z = 1.0 - 2.0 * (i + 0.5) / 40.0;
    double phi = i * 2.399963;
    glm::dvec3 n{std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z};
    IrradianceTruth e = world.irradiance(n, 0);
    for (int c = 0; c < 3; ++c) {
      EXPECT_LE(e.clipped[c], e.hdr[c] * (1 + 1e-12));
      EXPECT_GE(e.clipped[c], 0.0);
      largest_loss = std::max(largest_loss, 1.0 - e.clipped[c] / e.hdr[c]);
    }
  }
  // The sun carries ~3x the sky's irradiance but clips to at most 1/0.7 in
  // camera units: normals facing it must lose most of their light.
  EXPECT_GT(largest_loss, 0.5);
}

TEST(IrradianceTruth, RadianceTruthIsExposureTimesSceneRadianceAndClipsThroughTheBall) {
  SceneConfig scene = testing::smallScene();
  scene.rig.probe_reflectance = 0.5;
  World world(scene);
  auto environment = makeEnvironment("sun_sky");
  const glm::dvec3 sun_dir{std::cos(-120.0 * kPi / 180) * std::cos(40.0 * kPi / 180),
                           std::sin(-120.0 * kPi / 180) * std::cos(40.0 * kPi / 180), std::sin(40.0 * kPi / 180)};
  RadianceTruth sun = world.radiance(sun_dir, 0);
  EXPECT_NEAR(sun.hdr.g, environment->radiance(sun_dir).g * world.exposure(), 1e-9 * sun.hdr.g);
  EXPECT_NEAR(sun.clipped.g, 1.0 / 0.5, 1e-12);  // the ball shows at most 1, that is 2 once reflectance is undone
  // Straight down from the ball centre is plain floor (the tag is off to the side).
  RadianceTruth down = world.radiance({0, 0, -1}, 0);
  EXPECT_NEAR(down.hdr.g / world.exposure(),
              scene.floor_albedo * world.groundIrradianceUp(0).g / kPi,
              scene.floor_texture_contrast * scene.floor_albedo * world.groundIrradianceUp(0).g / kPi + 1e-12);
}

TEST(IrradianceTruth, LampSwitchesOnAndOffAtItsFrames) {
  SceneConfig scene = testing::smallScene();
  scene.environment = "overcast";
  scene.lighting.lamp_on_frame = 5;
  scene.lighting.lamp_off_frame = 10;
  World world(scene);
  EXPECT_FALSE(world.lighting(4).lamp_on);
  EXPECT_TRUE(world.lighting(5).lamp_on);
  EXPECT_TRUE(world.lighting(9).lamp_on);
  EXPECT_FALSE(world.lighting(10).lamp_on);
  // Toward the lamp (azimuth 200, elevation 35) the irradiance jumps; the
  // lamp's radiance is 40x the sky's mean over ~0.12 sr, so roughly +100%.
  const double az = 200.0 * kPi / 180, el = 35.0 * kPi / 180;
  glm::dvec3 toward_lamp{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  double off = world.irradiance(toward_lamp, 4).hdr.g;
  double on = world.irradiance(toward_lamp, 5).hdr.g;
  EXPECT_GT(on, 1.5 * off);
  EXPECT_DOUBLE_EQ(world.irradiance(toward_lamp, 10).hdr.g, off);
  // And the rendered frame brightens with it (exposure stays fixed).
  ImageRGB8 dark, bright;
  FrameTruth truth;
  world.render(4, dark, truth);
  world.render(5, bright, truth);
  double sum_dark = 0, sum_bright = 0;
  for (size_t i = 0; i < dark.pixels.size(); ++i) {
    sum_dark += dark.pixels[i];
    sum_bright += bright.pixels[i];
  }
  EXPECT_GT(sum_bright, 1.1 * sum_dark);
}

TEST(IrradianceTruth, SunAzimuthScriptRotatesTheEnvironment) {
  SceneConfig scene = testing::smallScene();
  scene.lighting.sun_azimuth_rate_deg_per_frame = 1.0;
  World world(scene);
  // After 90 frames the environment has turned 90 deg counter-clockwise: what
  // was seen toward +X (and its irradiance) is now toward +Y.
  glm::dvec3 x_dir = glm::normalize(glm::dvec3{1, 0, 0.3}), y_dir = glm::normalize(glm::dvec3{0, 1, 0.3});
  EXPECT_NEAR(world.radiance(y_dir, 90).hdr.b, world.radiance(x_dir, 0).hdr.b, 1e-9);
  // The sun at azimuth -120 deg moves to -30 deg.
  const double el = 40.0 * kPi / 180;
  glm::dvec3 sun_at_90{std::cos(el) * std::cos(-kPi / 6), std::cos(el) * std::sin(-kPi / 6), std::sin(el)};
  EXPECT_GT(world.radiance(sun_at_90, 90).hdr.g, 100.0 * world.radiance(sun_at_90, 0).hdr.g);
  // Ground irradiance does not depend on azimuth; grid cells are only
  // symmetric under whole-cell turns, so allow the discretisation's ~1e-3.
  EXPECT_NEAR(world.irradiance({0, 0, 1}, 37).hdr.g, world.irradiance({0, 0, 1}, 0).hdr.g,
              2e-3 * world.irradiance({0, 0, 1}, 0).hdr.g);
}

}  // namespace
}  // namespace probelight::sim
