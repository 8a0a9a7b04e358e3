// The lighting fit that run, analyze and render share (ibl::fitLighting): which
// map the dome is fitted from, what becomes the clipped lights, and when the
// border's reading is used. Synthetic maps: a sky of 0.4 and one sun of 300
// (a 6-degree cap), clipped for the 8-bit map where a camera would clip.
// (The border and the post on real frames: tests/app analyze and accuracy.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "ibl/cube_map.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/lighting_fit.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

const glm::dvec3 kSun = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));

CubeMapRGB skyWithSun(int n = 32) {
  CubeMapRGB map(n);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 omega = cubeTexelCenterDirection(face, x, y, n);
        double value = omega.z > 0.0 ? 0.4 : 0.04;
        if (glm::dot(omega, kSun) > std::cos(glm::radians(6.0))) value = 300.0;
        map.texel(face, x, y) = glm::vec3(static_cast<float>(value));
      }
  return map;
}

// The 8-bit map: nothing above the clip level of a camera's code 250.
CubeMapRGB clippedAt(CubeMapRGB map, double level) {
  for (auto& face : map.faces)
    for (glm::vec3& texel : face) texel = glm::min(texel, glm::vec3(static_cast<float>(level)));
  return map;
}

struct Fixture {
  LightingFitSettings settings;
  RigGeometry rig;
  double clip_level = clippedMapLevel(HdrMergeSettings{}, 1.0);
  CubeMapRGB hdr = skyWithSun();
  CubeMapRGB map_8bit = clippedAt(hdr, clip_level);
  MirrorBallView view = testing::kioskBallView(0.5, glm::dvec2(320.0, 240.0));

  LightingFitInputs inputs(bool with_view, bool with_bracket) const {
    LightingFitInputs in;
    in.map_8bit = &map_8bit;
    in.hdr_map = with_bracket ? &hdr : nullptr;
    in.view = with_view ? &view : nullptr;
    in.read_pixel = [](int, int) { return glm::u8vec3(40); };  // no pixel of the frame clipped
    in.rig = rig;
    return in;
  }
};

double angleDeg(const glm::dvec3& a, const glm::dvec3& b) { return glm::degrees(testing::angleBetweenRad(a, b)); }

TEST(LightingFit, WithoutTheFitFramesBallThe8BitMapIsFittedAsItIs) {
  const Fixture f;
  // A bracket cannot be used without the ball either: which of its texels
  // clipped in the frame is read from the ball's pixels.
  for (const bool with_bracket : {false, true}) {
    const LightingFit fit = fitLighting(f.inputs(false, with_bracket), f.settings);
    EXPECT_EQ(fit.method, LightingFitMethod::kEightBit);
    EXPECT_STREQ(toString(fit.method), "none");
    EXPECT_FALSE(fit.fitted_map);
    EXPECT_FALSE(fit.border);
    EXPECT_TRUE(fit.clipped_lights.empty());
    EXPECT_TRUE(fit.warnings.empty());
    ASSERT_EQ(fit.dome.size(), static_cast<std::size_t>(f.settings.dome.light_count));
    // The dome holds what the 8-bit map holds, and no more: its upward
    // irradiance is the map's (light_dome.hpp reproduces it exactly).
    double dome_up = 0.0;
    for (const DomeLight& light : fit.dome) dome_up += light.rgb.g * std::max(0.0, light.direction_w.z);
    EXPECT_NEAR(dome_up, irradianceFromCubeMap(f.map_8bit, {0.0, 0.0, 1.0}).g,
                1e-3 * irradianceFromCubeMap(f.map_8bit, {0.0, 0.0, 1.0}).g);
  }
}

TEST(LightingFit, ABracketIsFittedAndWhatItHoldsAboveTheClipBecomesTheClippedLights) {
  const Fixture f;
  const LightingFit fit = fitLighting(f.inputs(true, true), f.settings);
  EXPECT_EQ(fit.method, LightingFitMethod::kBracket);
  ASSERT_TRUE(fit.fitted_map);
  EXPECT_FALSE(fit.border) << "no ring given: the border is not read";
  EXPECT_TRUE(fit.warnings.empty());
  // One sun: one clipped light toward it (its cap's centroid, within half
  // a 32^2 texel, 1.4 deg), holding what the 8-bit map cut off.
  ASSERT_EQ(fit.clipped_lights.size(), 1u);
  EXPECT_LT(angleDeg(fit.clipped_lights[0].direction_w, kSun), 1.4);
  const double missing = irradianceFromCubeMap(f.hdr, kSun).g - irradianceFromCubeMap(f.map_8bit, kSun).g;
  EXPECT_NEAR(fit.clipped_lights[0].irradiance_rgb.g, missing, 0.02 * missing);
  // The dome and the dominant light come from the HDR map: the sun.
  EXPECT_TRUE(fit.dominant.found);
  EXPECT_LT(angleDeg(fit.dominant.direction_w, kSun), 5.0);
  double dome_up = 0.0;
  for (const DomeLight& light : fit.dome) dome_up += light.rgb.g * std::max(0.0, light.direction_w.z);
  EXPECT_NEAR(dome_up, irradianceFromCubeMap(f.hdr, {0.0, 0.0, 1.0}).g,
              1e-3 * irradianceFromCubeMap(f.hdr, {0.0, 0.0, 1.0}).g);
}

TEST(LightingFit, TheClippedLightsShadeAsEOverPiAtTheirScale) {
  ClippedLight light;
  light.direction_w = kSun;
  light.irradiance_rgb = glm::dvec3(3.0, 6.0, 9.0);
  SceneLighting lighting;
  lighting.clipped_diffuse_rgb[1] = glm::vec3(7.0f);  // left from an earlier fit: cleared
  setClippedLights(lighting, {light}, {0.5});
  EXPECT_NEAR(lighting.clipped_diffuse_rgb[0].g, 0.5 * 6.0 / std::numbers::pi, 1e-6);
  EXPECT_NEAR(glm::length(glm::dvec3(lighting.clipped_direction_w[0]) - kSun), 0.0, 1e-6);
  EXPECT_EQ(lighting.clipped_diffuse_rgb[1], glm::vec3(0.0f));
  setClippedLights(lighting, {light});  // no scale: 1
  EXPECT_NEAR(lighting.clipped_diffuse_rgb[0].b, 9.0 / std::numbers::pi, 1e-6);
}

}  // namespace
}  // namespace probelight::ibl
