// The dome of lights: irradiance it reproduces, where median cut puts lights
// against fixed regions, the dominant light from a clipped sky, and the
// degenerate inputs the kiosk must survive.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "ibl/color_transfer.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/light_dome.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

using testing::angleBetweenRad;

constexpr DomePlacement kPlacements[] = {DomePlacement::kFixedRegions, DomePlacement::kMedianCut,
                                         DomePlacement::kClustered};
using testing::fibonacciDirections;

glm::dvec3 direction(double azimuth_deg, double elevation_deg) {
  const double a = glm::radians(azimuth_deg), e = glm::radians(elevation_deg);
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

// A cube map of face size n filled from a radiance function (texel centres,
// 2x2 sub-samples so that small discs are not all-or-nothing).
CubeMapRGB cubeFrom(int n, const std::function<glm::dvec3(const glm::dvec3&)>& radiance) {
  CubeMapRGB cube(n);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        glm::dvec3 sum(0.0);
        for (int sy = 0; sy < 2; ++sy)
          for (int sx = 0; sx < 2; ++sx)
            sum += radiance(cubeCoordToDirection({face, (x + 0.25 + 0.5 * sx) / n, (y + 0.25 + 0.5 * sy) / n}));
        cube.texel(face, x, y) = glm::vec3(sum / 4.0);
      }
  return cube;
}

// A room: a sky brighter toward the zenith, a warm lamp of `lamp_radius_deg`
// (a disc) `lamp_times` the sky's radiance, a grey floor below the horizon.
glm::dvec3 room(const glm::dvec3& d, const glm::dvec3& lamp_direction, double lamp_radius_deg, double lamp_times) {
  if (d.z < 0.0) return glm::dvec3(0.12, 0.11, 0.10);
  glm::dvec3 sky = glm::dvec3(0.35, 0.42, 0.55) * (0.6 + 0.4 * d.z);
  if (angleBetweenRad(d, lamp_direction) < glm::radians(lamp_radius_deg)) sky += lamp_times * glm::dvec3(1.0, 0.9, 0.75);
  return sky;
}

// Irradiance from the upper hemisphere only: the dome's job.
glm::dvec3 upperIrradiance(const CubeMapRGB& cube, const glm::dvec3& normal) {
  CubeMapRGB upper = cube;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < cube.face_size; ++y)
      for (int x = 0; x < cube.face_size; ++x)
        if (cubeTexelCenterDirection(face, x, y, cube.face_size).z < 0.0) upper.texel(face, x, y) = glm::vec3(0.0f);
  return irradianceFromCubeMap(upper, normal);
}

std::vector<glm::dvec3> normalsAtLeastHalfUp() {
  std::vector<glm::dvec3> normals;
  for (const glm::dvec3& n : fibonacciDirections(200))
    if (n.z >= 0.5) normals.push_back(n);
  return normals;
}

TEST(LightDome, UniformSkyGivesExactIrradianceStraightUp) {
  const CubeMapRGB cube = cubeFrom(32, [](const glm::dvec3& d) { return d.z >= 0 ? glm::dvec3(1.0) : glm::dvec3(0.0); });
  for (DomePlacement placement : kPlacements) {
    for (int count : {1, 4, 8, 16}) {
      LightDomeSettings settings;
      settings.placement = placement;
      settings.light_count = count;
      const std::vector<DomeLight> lights = fitLightDome(cube, nullptr, settings);
      ASSERT_EQ(lights.size(), static_cast<std::size_t>(count));
      // Every region lies above the horizon of n = +Z, so the moment
      // construction is exact there: pi for L = 1, up to the bilinear
      // resampling of the cube at the horizon (a half-texel band where the
      // sampled radiance falls from 1 to 0: ~1% of the projected solid angle
      // at 32^2 faces... nearly none of the cosine weight, which is ~0 there).
      EXPECT_NEAR(luminance(domeIrradiance(lights, {0, 0, 1})), M_PI, 0.005 * M_PI)
          << toString(placement) << " " << count;
      for (const DomeLight& light : lights) {
        EXPECT_GE(light.direction_w.z, 0.0);
        EXPECT_NEAR(glm::length(light.direction_w), 1.0, 1e-9);
      }
    }
  }
}

// The requirement: at normals with z >= 0.5 the dome's irradiance is
// within 10% of the (upper-hemisphere) irradiance of the same map. Where a
// region lies wholly on one side of a normal's horizon the moment
// construction is exact; a region that straddles it loses the part below
// (Jensen's inequality: max(0, n . M) <= integral of L max(0, n . w)), so
// the dome errs low, and more so for larger regions: 8 lights make regions
// of ~30 degrees. In a room with a lamp and in a smooth sky the default
// (clustered) placement meets 10%. A 25 degree bright window (4x the sky)
// straddles many horizons: there 8 lights miss by up to 12%, and 16 meet
// it. Every placement's figures are printed, for comparing them.
TEST(LightDome, ReproducesTheUpperHemisphereIrradianceWithinTenPercent) {
  const glm::dvec3 lamp = direction(200.0, 35.0);
  struct World {
    const char* name;
    CubeMapRGB cube;
    int lights_needed;  // for the default placement to meet 10%
  };
  const std::vector<World> worlds = {
      {"lamp room", cubeFrom(64, [&](const glm::dvec3& d) { return room(d, lamp, 3.0, 60.0); }), 8},
      {"smooth sky", cubeFrom(64, [&](const glm::dvec3& d) { return room(d, lamp, 0.0, 0.0); }), 8},
      {"big window", cubeFrom(64, [&](const glm::dvec3& d) { return room(d, direction(80.0, 20.0), 25.0, 4.0); }), 16}};
  const std::vector<glm::dvec3> normals = normalsAtLeastHalfUp();
  for (const World& world : worlds) {
    std::vector<double> truth;
    for (const glm::dvec3& n : normals) truth.push_back(luminance(upperIrradiance(world.cube, n)));
    for (int count : {8, 16}) {
      for (DomePlacement placement : kPlacements) {
        LightDomeSettings settings;
        settings.placement = placement;
        settings.light_count = count;
        const std::vector<DomeLight> lights = fitLightDome(world.cube, nullptr, settings);
        double worst = 0.0, sum = 0.0;
        for (std::size_t i = 0; i < normals.size(); ++i) {
          const double error = std::abs(luminance(domeIrradiance(lights, normals[i])) - truth[i]) / truth[i];
          worst = std::max(worst, error);
          sum += error;
        }
        std::printf("[ dome     ] %-10s %-10s %2d lights: irradiance at %zu normals (z >= 0.5) mean %.2f%%, worst %.2f%%\n",
                    world.name, toString(placement), count, normals.size(), 100.0 * sum / normals.size(), 100.0 * worst);
        if (placement == LightDomeSettings{}.placement && count >= world.lights_needed) {
          EXPECT_LT(worst, 0.10) << world.name << " " << count;
        }
      }
    }
  }
}

// Seed B's weakness: a small bright lamp falls in a fixed region and its
// light is pulled toward the region's middle and spread over it (a too-soft
// shadow in the wrong place). Median cut with 8 lights makes regions of equal
// energy, so a lamp holding a quarter of the light is cut through into
// pieces that each mix with sky. Clustering gives the lamp a light of its
// own.
TEST(LightDome, ClusteringGivesASmallBrightLampItsOwnLight) {
  const glm::dvec3 lamp = direction(200.0, 35.0);
  const CubeMapRGB cube = cubeFrom(64, [&](const glm::dvec3& d) { return room(d, lamp, 2.0, 200.0); });
  double angle_deg[3] = {}, spread_deg[3] = {};
  for (DomePlacement placement : kPlacements) {
    LightDomeSettings settings;
    settings.placement = placement;
    const std::vector<DomeLight> lights = fitLightDome(cube, nullptr, settings);
    const DomeLight& brightest = *std::max_element(lights.begin(), lights.end(), [](const DomeLight& a, const DomeLight& b) {
      return luminance(a.rgb) < luminance(b.rgb);
    });
    const int k = static_cast<int>(placement);
    angle_deg[k] = glm::degrees(angleBetweenRad(brightest.direction_w, lamp));
    spread_deg[k] = glm::degrees(brightest.spread_rad);
    std::printf("[ dome     ] lamp of 2 deg, %-12s: brightest light %.2f deg from it, spread %.1f deg\n",
                toString(placement), angle_deg[k], spread_deg[k]);
  }
  const int fixed = static_cast<int>(DomePlacement::kFixedRegions), clustered = static_cast<int>(DomePlacement::kClustered);
  // Each light's direction is its region's first moment, so the sky its
  // region keeps pulls it off the lamp by about (sky share) x (sky's angle):
  // the tighter the region around the lamp, the nearer. Clustering must beat
  // both others on both counts, and median cut, which cuts the lamp, by far.
  // (Measured: fixed 4.5 / 5.0, median cut 20 / 19, clustered 2.2 / 3.1 deg.)
  const int median = static_cast<int>(DomePlacement::kMedianCut);
  EXPECT_LT(angle_deg[clustered], 0.6 * angle_deg[fixed]);
  EXPECT_LT(angle_deg[clustered], 0.25 * angle_deg[median]);
  EXPECT_LT(spread_deg[clustered], 0.7 * spread_deg[fixed]);
  EXPECT_LT(spread_deg[clustered], 0.25 * spread_deg[median]);
}

TEST(LightDome, BlindSpotIsFilledWithTheMeanSoTheEnergyStays) {
  const CubeMapRGB cube = cubeFrom(32, [](const glm::dvec3& d) { return d.z >= 0 ? glm::dvec3(1.0) : glm::dvec3(0.3); });
  // A 30 degree cap around a horizon direction unseen, and zeroed in the map.
  const glm::dvec3 blind = direction(0.0, 10.0);
  CubeMapRGB holed = cube;
  std::vector<float> validity(static_cast<std::size_t>(kCubeFaceCount) * 32 * 32, 1.0f);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        if (angleBetweenRad(cubeTexelCenterDirection(face, x, y, 32), blind) < glm::radians(30.0)) {
          holed.texel(face, x, y) = glm::vec3(0.0f);
          validity[static_cast<std::size_t>(face) * 32 * 32 + y * 32 + x] = 0.0f;
        }
  const double whole = luminance(domeIrradiance(fitLightDome(cube, nullptr), {0, 0, 1}));
  const double filled = luminance(domeIrradiance(fitLightDome(holed, &validity), {0, 0, 1}));
  const double ignored = luminance(domeIrradiance(fitLightDome(holed, nullptr), {0, 0, 1}));
  // The sky is uniform, so its mean is exact: only the sampling at the hole's
  // border (bilinear reads of zeroed texels) differs.
  EXPECT_NEAR(filled, whole, 0.01 * whole);
  EXPECT_LT(ignored, 0.97 * whole) << "without the validity the hole would read as darkness";
}

// The sun and the bright sky around it clip together into one blob, whose
// centre is the sun; a smaller bright patch elsewhere (a window, a white
// wall in the sun) clips too. Every clipped texel reads the same, so the
// largest blob is taken, and its centroid.
TEST(DominantLight, IsTheCentreOfTheLargestClippedBlob) {
  const glm::dvec3 sun = direction(-120.0, 40.0), patch = direction(60.0, 15.0);
  constexpr double kClip = 1.0;
  auto sky = [&](const glm::dvec3& d) {
    if (d.z < 0.0) return glm::dvec3(0.1);
    const double angle = glm::degrees(angleBetweenRad(d, sun));
    glm::dvec3 value = glm::dvec3(0.3, 0.4, 0.6) + 2.0 * std::exp(-angle / 9.0) * glm::dvec3(1.0);
    if (angle < 0.5) value += glm::dvec3(500.0);
    if (glm::degrees(angleBetweenRad(d, patch)) < 4.0) value += glm::dvec3(3.0);
    return glm::min(value, glm::dvec3(kClip));  // the 8-bit camera
  };
  const CubeMapRGB cube = cubeFrom(64, sky);
  const std::vector<DomeLight> lights = fitLightDome(cube, nullptr);
  const DominantLight dominant = findDominantLight(cube, nullptr, lights, kClip);
  ASSERT_TRUE(dominant.found);
  EXPECT_TRUE(dominant.from_clipped_region);
  const double error_deg = glm::degrees(angleBetweenRad(dominant.direction_w, sun));
  std::printf("[ dominant ] clipped blob of %.3f sr around the sun: centroid %.2f deg from it\n",
              dominant.clipped_solid_angle_sr, error_deg);
  // The blue channel clips first: 0.6 + 2 exp(-a/9) >= 0.98 within
  // a = 9 ln(2 / 0.38) = 14.9 degrees of the sun, a symmetric blob whose
  // centroid is the sun up to the 1.4 degree cells at its edge, which
  // average out around the ring.
  EXPECT_LT(error_deg, 0.5);
  // 14.9 degrees of radius: 0.211 sr, to within the edge cells (a ring of
  // 1.4 degrees is 0.04 sr; half of it either way); the patch is 0.015 sr.
  EXPECT_NEAR(dominant.clipped_solid_angle_sr, 2 * M_PI * (1 - std::cos(glm::radians(14.9))), 0.02);
  EXPECT_GT(luminance(dominant.rgb), 0.0);
}

TEST(DominantLight, WithoutClippingItIsThePeakRadiance) {
  const glm::dvec3 lamp = direction(30.0, 50.0);
  const CubeMapRGB cube = cubeFrom(32, [&](const glm::dvec3& d) { return room(d, lamp, 4.0, 0.5); });
  const std::vector<DomeLight> lights = fitLightDome(cube, nullptr);
  const DominantLight dominant = findDominantLight(cube, nullptr, lights, 10.0);  // nothing reaches 10
  ASSERT_TRUE(dominant.found);
  EXPECT_FALSE(dominant.from_clipped_region);
  EXPECT_LT(glm::degrees(angleBetweenRad(dominant.direction_w, lamp)), 5.0);
}

// Stress: all finite and sensible.
TEST(LightDomeStress, DegenerateEnvironmentsGiveFiniteLights) {
  auto expectFinite = [](const std::vector<DomeLight>& lights, const char* what) {
    for (const DomeLight& light : lights) {
      EXPECT_TRUE(std::isfinite(light.direction_w.x) && std::isfinite(light.direction_w.y) &&
                  std::isfinite(light.direction_w.z))
          << what;
      EXPECT_TRUE(std::isfinite(light.rgb.r) && light.rgb.r >= 0.0) << what;
      EXPECT_TRUE(std::isfinite(light.spread_rad)) << what;
      EXPECT_GE(light.direction_w.z, 0.0) << what;
    }
  };
  for (DomePlacement placement : kPlacements) {
    LightDomeSettings settings;
    settings.placement = placement;
    // All black.
    const CubeMapRGB black = cubeFrom(16, [](const glm::dvec3&) { return glm::dvec3(0.0); });
    std::vector<DomeLight> lights = fitLightDome(black, nullptr, settings);
    ASSERT_EQ(lights.size(), 8u);
    expectFinite(lights, "black");
    EXPECT_EQ(luminance(domeIrradiance(lights, {0, 0, 1})), 0.0);
    EXPECT_FALSE(findDominantLight(black, nullptr, lights, 1.0).found);
    // A single bright texel: one light carries it all.
    CubeMapRGB one = black;
    one.texel(4, 5, 9) = glm::vec3(1000.0f);
    lights = fitLightDome(one, nullptr, settings);
    expectFinite(lights, "single texel");
    int lit = 0;
    for (const DomeLight& light : lights) lit += luminance(light.rgb) > 0.0 ? 1 : 0;
    EXPECT_GE(lit, 1);
    // NaN and infinite texels count as nothing.
    CubeMapRGB bad = cubeFrom(16, [](const glm::dvec3&) { return glm::dvec3(1.0); });
    bad.texel(4, 3, 3) = glm::vec3(std::numeric_limits<float>::quiet_NaN());
    bad.texel(0, 8, 2) = glm::vec3(std::numeric_limits<float>::infinity());
    lights = fitLightDome(bad, nullptr, settings);
    expectFinite(lights, "nan/inf");
    // A lamp exactly at the horizon: its light stays at z >= 0 (on the
    // horizon, where the ground sees it edge-on).
    const CubeMapRGB horizon = cubeFrom(32, [](const glm::dvec3& d) {
      return std::abs(d.z) < 0.02 && d.x > 0.99 ? glm::dvec3(100.0) : glm::dvec3(0.0);
    });
    lights = fitLightDome(horizon, nullptr, settings);
    expectFinite(lights, "horizon lamp");
    // An empty map and a count of zero.
    EXPECT_TRUE(fitLightDome(CubeMapRGB(0), nullptr, settings).size() == 8u);
    settings.light_count = 0;
    EXPECT_TRUE(fitLightDome(black, nullptr, settings).empty());
    // Many lights on a tiny grid: no more regions than cells is fine, never a crash.
    settings.light_count = 64;
    settings.azimuth_cells = 4;
    settings.elevation_cells = 2;
    lights = fitLightDome(one, nullptr, settings);
    expectFinite(lights, "more lights than cells");
    EXPECT_LE(lights.size(), 64u);
  }
}

}  // namespace
}  // namespace probelight::ibl
