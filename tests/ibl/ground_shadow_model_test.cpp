// The ground-shadow model (ibl/ground_shadow.hpp): light shares, the region
// the shadows reach, the CPU reference against closed forms, and why the
// composite is a ratio and not seed B's subtraction.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "ibl/color_transfer.hpp"
#include "ibl/ground_shadow.hpp"

namespace probelight::ibl {
namespace {

DomeLight domeLight(const glm::dvec3& direction, double brightness, double spread_rad = 0.0) {
  DomeLight light;
  light.direction_w = glm::normalize(direction);
  light.rgb = glm::dvec3(brightness);
  light.spread_rad = spread_rad;
  return light;
}

TEST(GroundShadowModel, SharesAreEachLightsPartOfTheGroundIrradianceAndFaintOrLowLightsAreDropped) {
  const std::vector<DomeLight> dome = {domeLight({0, 0, 1}, 1.0), domeLight({1, 0, 1}, 2.0), domeLight({0, 1, 0}, 5.0),
                                       domeLight({0, -1, 0.001}, 1e-3)};
  const std::vector<ShadowLight> lights = groundShadowLights(dome);
  // E = 1 * 1 + 2 * cos 45 + 5 * 0 + tiny: the horizontal light gives the
  // ground nothing and the faint one under 1/255 of it: both dropped.
  ASSERT_EQ(lights.size(), 2u);
  const double e = 1.0 + 2.0 * std::sqrt(0.5) + 1e-3 * 0.001;
  EXPECT_NEAR(lights[0].share_rgb.g, 1.0 / e, 1e-9);
  EXPECT_NEAR(lights[1].share_rgb.g, 2.0 * std::sqrt(0.5) / e, 1e-9);
  EXPECT_TRUE(groundShadowLights({domeLight({0, 0, 1}, 0.0)}).empty()) << "an all-black environment casts nothing";
  DomeLight bad = domeLight({0, 0, 1}, 1.0);
  bad.rgb.r = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(groundShadowLights({bad}).empty());
}

TEST(GroundShadowModel, ConeRadiusIsTheUniformDiscWithTheRegionsHalfEnergyAngle) {
  // A uniform disc of radius a holds half its energy within a / sqrt(2).
  EXPECT_NEAR(coneRadiusFor(domeLight({0, 0, 1}, 1.0, 0.1 / std::sqrt(2.0)), 0.0), 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(coneRadiusFor(domeLight({0, 0, 1}, 1.0, 0.0), 0.004), 0.004);
}

TEST(GroundShadowModel, RegionReachesTheLongestShadowAndIsCappedForLowLights) {
  ShadowCaster sphere;
  sphere.radius_m = 0.05;
  ShadowLight high;
  high.direction_w = {0, 0, 1};
  GroundRegion region = groundShadowRegion(sphere, {high}, 1.0);
  EXPECT_NEAR(region.half_size_m, 1.05 * 0.05, 1e-9);
  ShadowLight low;
  low.direction_w = glm::normalize(glm::dvec3(1, 0, std::tan(glm::radians(30.0))));  // 30 deg up
  region = groundShadowRegion(sphere, {low}, 1.0);
  // The top (0.1 m) cast at 30 degrees lands 0.1 / tan 30 away, plus the radius.
  EXPECT_NEAR(region.half_size_m, 1.05 * (0.1 / std::tan(glm::radians(30.0)) + 0.05), 1e-9);
  ShadowLight horizon;
  horizon.direction_w = {1, 0, 0};
  EXPECT_DOUBLE_EQ(groundShadowRegion(sphere, {horizon}, 0.3).half_size_m, 0.3);
}

TEST(GroundShadowModel, ReferenceMatchesClosedForms) {
  ShadowCaster sphere;
  sphere.radius_m = 0.04;
  ShadowLight overhead;
  overhead.direction_w = {0, 0, 1};
  overhead.share_rgb = glm::dvec3(0.6);
  // A point light straight up: the disc under the sphere loses the share.
  EXPECT_DOUBLE_EQ(groundLightFraction({0.03, 0.0}, sphere, {overhead}).g, 0.4);
  EXPECT_DOUBLE_EQ(groundLightFraction({0.05, 0.0}, sphere, {overhead}).g, 1.0);
  // A wide cone straight up, seen from under the sphere's middle at height
  // 0: the sphere (centre 0.04 up, radius 0.04) hides every direction within
  // 90 degrees... all of a 30 degree cone; from 0.12 m away it subtends
  // asin(0.04 / |(0.12, 0.04)|) = 18.4 deg around elevation 18.4 deg: none of it.
  overhead.cone_radius_rad = glm::radians(30.0);
  EXPECT_NEAR(groundLightFraction({0.0, 0.0}, sphere, {overhead}, 1024).g, 0.4, 1e-9);
  EXPECT_NEAR(groundLightFraction({0.12, 0.0}, sphere, {overhead}, 1024).g, 1.0, 1e-9);
  // A box: straight under it nothing arrives, beside it everything.
  ShadowCaster box;
  box.shape = ShadowCaster::Shape::kBox;
  box.box_size_m = {0.04, 0.02, 0.03};
  box.box_yaw_rad = glm::radians(90.0);  // turned: its long side now along y
  overhead.cone_radius_rad = 0.0;
  EXPECT_DOUBLE_EQ(groundLightFraction({0.0, 0.015}, box, {overhead}).g, 0.4);
  EXPECT_DOUBLE_EQ(groundLightFraction({0.015, 0.0}, box, {overhead}).g, 1.0);
}

// Seed B subtracted the shadow buffer from the camera pixel, scaled for a
// white floor. In linear light, a floor of albedo rho under irradiance E
// reads rho E / pi; the shadowed truth is rho (E - R) / pi. The ratio form
// gives exactly that for any rho; subtraction takes off (R / E) of a white
// floor's value, so a dark floor goes black and a coloured one changes hue.
TEST(GroundShadowModel, RatioCompositeIsRightForAnyFloorAndSubtractionIsNot) {
  const double irradiance_over_pi = 0.6;  // linear camera units for albedo 1
  const glm::dvec3 fraction(0.7);         // 30% of the light blocked
  const glm::dvec3 white_floor(irradiance_over_pi);
  struct Floor {
    const char* name;
    glm::dvec3 albedo;
  };
  for (const Floor& floor : {Floor{"white", glm::dvec3(1.0)}, Floor{"dark grey", glm::dvec3(0.1)},
                             Floor{"terracotta", glm::dvec3(0.6, 0.3, 0.1)}}) {
    const glm::dvec3 pixel = floor.albedo * irradiance_over_pi;
    const glm::dvec3 truth = floor.albedo * irradiance_over_pi * fraction;
    const glm::dvec3 ratio = compositeByRatio(pixel, fraction);
    const glm::dvec3 subtracted = compositeBySubtraction(pixel, fraction, white_floor);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ratio[c], truth[c], 1e-12) << floor.name;
    const double subtraction_error = glm::length(subtracted - truth) / glm::length(truth);
    std::printf("[ composite] %-10s floor: ratio exact; subtraction off by %.0f%%\n", floor.name, 100.0 * subtraction_error);
    if (floor.albedo == glm::dvec3(1.0)) {
      EXPECT_LT(subtraction_error, 1e-12) << "subtraction is right for a white floor only";
    } else {
      EXPECT_GT(subtraction_error, 0.5) << floor.name;
    }
  }
  // The dark floor goes black under subtraction: 0.06 - 0.3 * 0.6 < 0.
  EXPECT_EQ(compositeBySubtraction(glm::dvec3(0.06), fraction, white_floor), glm::dvec3(0.0));
  // The terracotta floor's hue changes: its blue goes to 0 while red keeps some.
  const glm::dvec3 terracotta = compositeBySubtraction(glm::dvec3(0.36, 0.18, 0.06), fraction, white_floor);
  EXPECT_EQ(terracotta.b, 0.0);
  EXPECT_GT(terracotta.r, 0.0);
}

}  // namespace
}  // namespace probelight::ibl
