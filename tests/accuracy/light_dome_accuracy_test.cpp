// The dome of lights on the simulated worlds, both real HDR ones included:
// how well 8 lights reproduce the upper hemisphere's irradiance of what an
// 8-bit camera can know (the clipped radiance), at normals with z >= 0.5.
//
// Input: a 64^2 cube of the clipped radiance straight from the simulator
// (no ball, so that this measures the dome, not the probe; the probe's own
// error is in irradiance_accuracy_test). Reference: the same radiance
// integrated by brute force over a 720 x 180 grid of the upper hemisphere.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "accuracy_test_support.hpp"
#include "ibl/light_dome.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

using testing::luminance;

TEST(LightDomeAccuracy, EightLightsHoldTheUpperIrradianceOfEveryWorld) {
  const std::string data = PROBELIGHT_TEST_DATA_DIR;
  const std::vector<std::string> environments = {"sun_sky", "studio", "overcast", "coloured_wall",
                                                 data + "/env/KernerEnvLatLong.exr", data + "/env/StageEnvLatLong.exr"};
  // 50 normals with z >= 0.5 (a Fibonacci spiral over the whole sphere, kept where z >= 0.5).
  std::vector<glm::dvec3> normals;
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < 200; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / 200.0, ring = std::sqrt(1.0 - z * z);
    if (z >= 0.5) normals.push_back({ring * std::cos(golden_angle * i), ring * std::sin(golden_angle * i), z});
  }
  std::printf("\n| world | placement | mean | worst normal |\n|---|---|---|---|\n");
  for (const std::string& environment : environments) {
    sim::SceneConfig scene = sim::defaultScene();
    scene.environment = environment;
    const sim::World world(scene);
    constexpr int kFace = 64;
    ibl::CubeMapRGB cube(kFace);
    for (int face = 0; face < ibl::kCubeFaceCount; ++face)
      for (int y = 0; y < kFace; ++y)
        for (int x = 0; x < kFace; ++x) {
          glm::dvec3 sum(0.0);
          for (int sy = 0; sy < 2; ++sy)
            for (int sx = 0; sx < 2; ++sx)
              sum += world.radiance(ibl::cubeCoordToDirection({face, (x + 0.25 + 0.5 * sx) / kFace, (y + 0.25 + 0.5 * sy) / kFace}), 0)
                         .clipped;
          cube.texel(face, x, y) = glm::vec3(sum / 4.0);
        }
    std::vector<double> truth(normals.size(), 0.0);
    constexpr int kWidth = 720, kHeight = 180;
    for (int row = 0; row < kHeight; ++row) {
      const double e0 = 0.5 * M_PI * row / kHeight, e1 = 0.5 * M_PI * (row + 1) / kHeight, e = 0.5 * (e0 + e1);
      const double solid = (std::sin(e1) - std::sin(e0)) * 2.0 * M_PI / kWidth;
      for (int column = 0; column < kWidth; ++column) {
        const double a = 2.0 * M_PI * (column + 0.5) / kWidth;
        const glm::dvec3 d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
        const double L = luminance(world.radiance(d, 0).clipped);
        for (std::size_t k = 0; k < normals.size(); ++k) truth[k] += L * std::max(0.0, glm::dot(d, normals[k])) * solid;
      }
    }
    const std::string name = environment.substr(environment.find_last_of('/') + 1);
    for (ibl::DomePlacement placement :
         {ibl::DomePlacement::kFixedRegions, ibl::DomePlacement::kMedianCut, ibl::DomePlacement::kClustered}) {
      ibl::LightDomeSettings settings;
      settings.placement = placement;
      const std::vector<ibl::DomeLight> lights = ibl::fitLightDome(cube, nullptr, settings);
      double mean = 0.0, worst = 0.0;
      for (std::size_t k = 0; k < normals.size(); ++k) {
        const double error = std::abs(luminance(ibl::domeIrradiance(lights, normals[k])) - truth[k]) / truth[k];
        mean += error / normals.size();
        worst = std::max(worst, error);
      }
      std::printf("| %s | %s | %.1f%% | %.1f%% |\n", name.c_str(), ibl::toString(placement), 100.0 * mean, 100.0 * worst);
      // The bound, for the default placement: the dome within 10%
      // of the upper-hemisphere irradiance at every normal with z >= 0.5.
      // (The cube's own 1.4 degree texels account for up to ~3.6% straight
      // up in the Stage world's small bright lamps; the rest is the regions
      // that straddle a normal's horizon.)
      if (placement == ibl::LightDomeSettings{}.placement) {
        EXPECT_LT(worst, 0.10) << name;
      }
    }
  }
}

}  // namespace
}  // namespace probelight
