// The tag's white border as a diffuse reference, on synthetic maps and
// frames whose light is known exactly: a uniform sky plus a small sun that
// an 8-bit camera clips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math_constants.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/white_reference.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

// A sky of radiance `sky` with suns (cap radius 6 deg) of radiance `sun`.
CubeMapRGB skyWithSuns(const std::vector<glm::dvec3>& suns, double sky, double sun, int n = 32) {
  CubeMapRGB map(n);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 omega = cubeTexelCenterDirection(face, x, y, n);
        double value = omega.z > 0.0 ? sky : 0.1 * sky;
        for (const glm::dvec3& s : suns)
          if (glm::dot(omega, glm::normalize(s)) > std::cos(glm::radians(6.0))) value = sun;
        map.texel(face, x, y) = glm::vec3(static_cast<float>(value));
      }
  return map;
}

CubeMapRGB clip(CubeMapRGB map, float level) {
  for (auto& face : map.faces)
    for (glm::vec3& texel : face) texel = glm::min(texel, glm::vec3(level));
  return map;
}

// Upper-hemisphere irradiance, as the ground sees it.
glm::dvec3 upwardIrradiance(const CubeMapRGB& map) {
  glm::dvec3 sum(0.0);
  const int n = map.face_size;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 omega = cubeTexelCenterDirection(face, x, y, n);
        if (omega.z > 0.0) sum += glm::dvec3(map.texel(face, x, y)) * omega.z * cubeTexelSolidAngle(x, y, n);
      }
  return sum;
}

WhiteBorderReading borderReading(const glm::dvec3& linear) {
  WhiteBorderReading reading;
  reading.status = WhiteBorderStatus::kMeasured;
  reading.linear_rgb = linear;
  return reading;
}

TEST(WhiteReference, TheShortfallGoesToTheClippedSunAndTheGroundGetsItsLight) {
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const CubeMapRGB truth = skyWithSuns({sun}, 0.4, 300.0);
  CubeMapRGB map = clip(truth, 1.0f);
  const glm::dvec3 e_true = upwardIrradiance(truth);
  const double albedo = 0.85;
  // The border's camera value: albedo * E / pi.
  const WhiteReferenceResult result =
      correctClippedWithWhiteBorder(map, nullptr, borderReading(albedo * e_true / kPi), albedo, 1.0);
  ASSERT_EQ(result.status, WhiteReferenceStatus::kCorrected) << result.message;
  EXPECT_NEAR(result.clipped_lower_sr, 0.0, 1e-12);
  // By construction the ground now gets exactly the border's light.
  EXPECT_NEAR(upwardIrradiance(map).g / e_true.g, 1.0, 1e-5);
  // Only the sun clipped, so the light went there: every normal is lit as
  // by the truth (the sun's cap is sharp, so a small quadrature error stays).
  for (const glm::dvec3& normal : testing::fibonacciDirections(40)) {
    const double expected = irradianceFromCubeMap(truth, normal).g;
    EXPECT_NEAR(irradianceFromCubeMap(map, normal).g, expected, 1e-3 * expected + 1e-6) << normal.x << " " << normal.z;
  }
  // Without the correction the normal facing the sun misses most of it.
  EXPECT_LT(irradianceFromCubeMap(clip(truth, 1.0f), sun).g, 0.3 * irradianceFromCubeMap(truth, sun).g);
}

TEST(WhiteReference, ShadowedBordersNothingClippedAndUnreadBordersLeaveTheMapAlone) {
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.3, -0.5, 0.8));
  const CubeMapRGB truth = skyWithSuns({sun}, 0.4, 300.0);
  const CubeMapRGB clipped = clip(truth, 1.0f);
  const double albedo = 0.85;
  const glm::dvec3 e_clipped = upwardIrradiance(clipped);
  auto unchanged = [&](const CubeMapRGB& map) { return map.faces == clipped.faces; };
  {
    // A border in shadow reads less than even the clipped ball.
    CubeMapRGB map = clipped;
    const auto result = correctClippedWithWhiteBorder(map, nullptr, borderReading(0.5 * albedo * e_clipped / kPi),
                                                      albedo, 1.0);
    EXPECT_EQ(result.status, WhiteReferenceStatus::kBorderDarker);
    EXPECT_NE(result.message.find("shadow"), std::string::npos);
    EXPECT_TRUE(unchanged(map));
  }
  {
    // Within the tolerance below: the two agree, nothing to add.
    CubeMapRGB map = clipped;
    const auto result = correctClippedWithWhiteBorder(map, nullptr, borderReading(0.95 * albedo * e_clipped / kPi),
                                                      albedo, 1.0);
    EXPECT_EQ(result.status, WhiteReferenceStatus::kNoShortfall);
    EXPECT_TRUE(unchanged(map));
  }
  {
    WhiteBorderReading unread;
    unread.status = WhiteBorderStatus::kClipped;
    unread.message = "clipped";
    CubeMapRGB map = clipped;
    EXPECT_EQ(correctClippedWithWhiteBorder(map, nullptr, unread, albedo, 1.0).status,
              WhiteReferenceStatus::kBorderUnusable);
    EXPECT_TRUE(unchanged(map));
  }
  {
    CubeMapRGB overcast = skyWithSuns({}, 0.4, 0.0);
    const CubeMapRGB before = overcast;
    const auto result = correctClippedWithWhiteBorder(overcast, nullptr,
                                                      borderReading(albedo * upwardIrradiance(before) / kPi), albedo, 1.0);
    EXPECT_EQ(result.status, WhiteReferenceStatus::kNothingClipped);
    EXPECT_NE(result.message.find("100%"), std::string::npos) << result.message;
    EXPECT_TRUE(overcast.faces == before.faces);
  }
  {
    // A sun hidden from the ball (validity 0) is neither counted nor changed.
    const int n = clipped.face_size;
    std::vector<float> validity(static_cast<std::size_t>(kCubeFaceCount) * n * n, 1.0f);
    for (int face = 0; face < kCubeFaceCount; ++face)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          if (clipped.texel(face, x, y).g >= 1.0f) validity[static_cast<std::size_t>(face) * n * n + y * n + x] = 0.0f;
    CubeMapRGB map = clipped;
    const auto result = correctClippedWithWhiteBorder(map, &validity, borderReading(albedo * upwardIrradiance(truth) / kPi),
                                                      albedo, 1.0);
    EXPECT_EQ(result.status, WhiteReferenceStatus::kNothingClipped);
    EXPECT_TRUE(unchanged(map));
  }
}

TEST(WhiteReference, ClippedLightsHoldTheMissingEnergyWhereItWas) {
  const std::vector<glm::dvec3> suns = {glm::normalize(glm::dvec3(0.3, -0.5, 0.8)),
                                        glm::normalize(glm::dvec3(-0.8, 0.1, 0.4))};
  const CubeMapRGB truth = skyWithSuns(suns, 0.4, 300.0);
  const CubeMapRGB clipped = clip(truth, 1.0f);
  const std::vector<ClippedLight> lights = clippedLights(truth, clipped, nullptr, 1.0);
  ASSERT_EQ(lights.size(), 2u);
  for (const glm::dvec3& sun : suns) {
    const ClippedLight* nearest = &lights[0];
    for (const ClippedLight& light : lights)
      if (glm::dot(light.direction_w, sun) > glm::dot(nearest->direction_w, sun)) nearest = &light;
    // The cap's centroid is its centre up to the texel grid: the texels
    // whose centres fall in the cap are not symmetric about it; half a
    // texel of this 32^2 map (90 / 32 = 2.8 deg) bounds that.
    EXPECT_LT(glm::degrees(testing::angleBetweenRad(nearest->direction_w, sun)), 1.4);
  }
  // The clipped map plus the lights reproduces the truth's irradiance at
  // every normal that sees both suns whole; elsewhere within the suns' caps.
  for (const glm::dvec3& normal : testing::fibonacciDirections(60)) {
    double with_lights = irradianceFromCubeMap(clipped, normal).g;
    for (const ClippedLight& light : lights) with_lights += light.irradiance_rgb.g * std::max(0.0, glm::dot(normal, light.direction_w));
    const double expected = irradianceFromCubeMap(truth, normal).g;
    bool sees_both_whole = true;
    for (const glm::dvec3& sun : suns) sees_both_whole &= glm::dot(normal, sun) > std::sin(glm::radians(7.0));
    // A 6-deg cap cut by the horizon: at most its whole energy is misplaced.
    const double tolerance = sees_both_whole ? 1e-3 * expected : 0.5 * 300.0 * 2.0 * kPi * (1.0 - std::cos(glm::radians(6.0)));
    EXPECT_NEAR(with_lights, expected, tolerance + 1e-6);
  }
  // Six suns, four lights at most: the energy (first moment) is all kept.
  std::vector<glm::dvec3> six;
  for (int k = 0; k < 6; ++k) six.push_back(glm::dvec3(std::cos(k * kPi / 3.0) * 0.6, std::sin(k * kPi / 3.0) * 0.6, 0.8));
  const CubeMapRGB truth6 = skyWithSuns(six, 0.4, 300.0);
  const std::vector<ClippedLight> four = clippedLights(truth6, clip(truth6, 1.0f), nullptr, 1.0, nullptr, 4);
  ASSERT_EQ(four.size(), 4u);
  glm::dvec3 moment(0.0), expected_moment(0.0);
  for (const ClippedLight& light : four) moment += light.irradiance_rgb.g * light.direction_w;
  const int n = truth6.face_size;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double extra = std::max(0.0, truth6.texel(face, x, y).g - 1.0);
        expected_moment += extra * cubeTexelSolidAngle(x, y, n) * cubeTexelCenterDirection(face, x, y, n);
      }
  // Merged clusters keep their moment; projecting it onto one direction
  // loses only the part across it (suns 60 deg apart merged: cos(30) of it
  // at worst), so the total is kept along z exactly enough to test.
  EXPECT_NEAR(moment.z, expected_moment.z, 0.15 * expected_moment.z);
  // And nothing clipped gives no light.
  const CubeMapRGB overcast = skyWithSuns({}, 0.4, 0.0);
  EXPECT_TRUE(clippedLights(overcast, overcast, nullptr, 1.0).empty());
}

// A camera looking down at the tag; each pixel's value comes from the
// ground point its ray hits: the ring at `white` (linear), elsewhere grey.
struct SyntheticView {
  CameraIntrinsics camera;
  PoseCamFromWorld pose;
  WhiteRing ring = tagWhiteRing(8, false, 0.08);

  explicit SyntheticView(double height_m) {
    camera.width_px = 320;
    camera.height_px = 240;
    camera.fx_px = camera.fy_px = 300.0;
    camera.cx_px = 159.5;
    camera.cy_px = 119.5;
    pose = testing::poseSeeingPointAtPixel(camera, glm::dvec3(0.05, -0.6 * height_m, height_m), glm::dvec3(0.0),
                                           glm::dvec2(camera.cx_px, camera.cy_px));
  }
  glm::dvec2 ground(int x, int y) const {
    const glm::dvec3 ray_w = glm::transpose(pose.R_cam_from_world) *
                             glm::dvec3((x - camera.cx_px) / camera.fx_px, (y - camera.cy_px) / camera.fy_px, 1.0);
    const glm::dvec3 eye = pose.cameraCenterWorld();
    return glm::dvec2(eye + (-eye.z / ray_w.z) * ray_w);
  }
  bool inRing(const glm::dvec2& p) const {
    const double m = std::max(std::abs(p.x), std::abs(p.y));
    return m >= ring.inner_half_m && m <= ring.outer_half_m;
  }
  // `white` is the ring's linear value at ground point p.
  template <typename WhiteAt>
  RgbPixelReader reader(WhiteAt white) const {
    return [this, white](int x, int y) {
      const glm::dvec2 p = ground(x, y);
      const double linear = inRing(p) ? white(p) : 0.05;
      const auto code = static_cast<std::uint8_t>(std::lround(255.0 * linearToSrgb(std::min(1.0, linear))));
      return glm::u8vec3(code);
    };
  }
};

TEST(WhiteReference, TheBorderIsReadWithItsShadowLeftOutAndItsFailuresNamed) {
  const SyntheticView view(0.35);
  const WhiteBorderSettings settings;
  {
    const WhiteBorderReading reading =
        readWhiteBorder(view.camera, view.pose, view.ring, view.reader([](glm::dvec2) { return 0.5; }), settings);
    ASSERT_EQ(reading.status, WhiteBorderStatus::kMeasured) << reading.message;
    EXPECT_EQ(reading.patches, 16);
    EXPECT_EQ(reading.patches_lit, 16);
    // Rounding to a code: half a step of the sRGB curve at 0.5 is < 0.3%.
    EXPECT_NEAR(reading.linear_rgb.g, 0.5, 0.003);
  }
  {
    // A shadow over the -X side and part of +Y: those patches are left
    // out, the lit level still read.
    const WhiteBorderReading reading = readWhiteBorder(
        view.camera, view.pose, view.ring, view.reader([](glm::dvec2 p) { return p.x < -0.01 ? 0.15 : 0.5; }), settings);
    ASSERT_EQ(reading.status, WhiteBorderStatus::kMeasured) << reading.message;
    EXPECT_GE(reading.patches_shadowed, 5);
    EXPECT_NEAR(reading.linear_rgb.g, 0.5, 0.003);
  }
  {
    const WhiteBorderReading reading =
        readWhiteBorder(view.camera, view.pose, view.ring, view.reader([](glm::dvec2) { return 1.5; }), settings);
    EXPECT_EQ(reading.status, WhiteBorderStatus::kClipped);
    EXPECT_NE(reading.message.find("clipped"), std::string::npos);
  }
  {
    const WhiteBorderReading reading =
        readWhiteBorder(view.camera, view.pose, view.ring, view.reader([](glm::dvec2) { return 0.0; }), settings);
    EXPECT_EQ(reading.status, WhiteBorderStatus::kTooDark);
  }
  {
    // 30 m away the ring is a fraction of a pixel.
    const SyntheticView far(30.0);
    const WhiteBorderReading reading =
        readWhiteBorder(far.camera, far.pose, far.ring, far.reader([](glm::dvec2) { return 0.5; }), settings);
    EXPECT_EQ(reading.status, WhiteBorderStatus::kTooSmall);
  }
  {
    // Looking the other way: no patch in the frame.
    SyntheticView away(0.35);
    away.pose.t_cam_from_world += glm::dvec3(5.0, 0.0, 0.0);
    const WhiteBorderReading reading =
        readWhiteBorder(away.camera, away.pose, away.ring, away.reader([](glm::dvec2) { return 0.5; }), settings);
    EXPECT_EQ(reading.status, WhiteBorderStatus::kNotInView);
  }
}

}  // namespace
}  // namespace probelight::ibl

namespace probelight::ibl {
namespace {

TEST(WhiteReference, AClippedLightIsStillThereWhileItsTexelsClip) {
  const std::vector<glm::dvec3> suns = {glm::normalize(glm::dvec3(0.3, -0.5, 0.8)),
                                        glm::normalize(glm::dvec3(-0.8, 0.1, 0.4))};
  const CubeMapRGB truth = skyWithSuns(suns, 0.4, 300.0);
  const CubeMapRGB clipped = clip(truth, 1.0f);
  const std::vector<ClippedLight> lights = clippedLights(truth, clipped, nullptr, 1.0);
  ASSERT_EQ(lights.size(), 2u);
  for (const ClippedLight& light : lights) {
    ASSERT_FALSE(light.texels.empty());
    double total = 0.0;
    for (const float share : light.texel_share) total += share;
    EXPECT_NEAR(total, 1.0, 1e-5);
    // The same map: all of it still clips.
    EXPECT_NEAR(stillClippedShare(light, clipped, 1.0), 1.0, 1e-5);
  }
  // The second sun goes behind a cloud: its light is gone, the first's stays.
  const CubeMapRGB later = clip(skyWithSuns({suns[0]}, 0.4, 300.0), 1.0f);
  for (const ClippedLight& light : lights) {
    const bool first = glm::dot(light.direction_w, suns[0]) > 0.99;
    EXPECT_NEAR(stillClippedShare(light, later, 1.0), first ? 1.0 : 0.0, 1e-5);
  }
  // A map of another size says nothing is there.
  EXPECT_EQ(stillClippedShare(lights[0], CubeMapRGB(4), 1.0), 0.0);
}

// A map clamped at a clip level holds it as its storage rounds it: 0.7 is
// 0.69999999 as a float (below the double), and a half float rounds by up
// to 1/2048 either way. Each still clips; a texel 1% below (about one 8-bit
// code at the top) does not.
TEST(WhiteReference, ATexelClampedAtTheClipLevelClipsInEveryStorage) {
  const double clip_level = 0.7;
  ASSERT_LT(static_cast<double>(static_cast<float>(clip_level)), clip_level) << "the case this test is for";
  ClippedLight light;
  light.texels = {0};
  light.texel_share = {1.0f};
  for (const double stored : {static_cast<double>(static_cast<float>(clip_level)), clip_level * (1.0 - 1.0 / 4096.0),
                              clip_level * (1.0 + 1.0 / 4096.0)}) {
    CubeMapRGB live(4);
    live.faces[0][0] = glm::vec3(static_cast<float>(stored), 0.1f, 0.1f);
    EXPECT_EQ(stillClippedShare(light, live, clip_level), 1.0) << stored;
  }
  CubeMapRGB below(4);
  below.faces[0][0] = glm::vec3(static_cast<float>(0.99 * clip_level));
  EXPECT_EQ(stillClippedShare(light, below, clip_level), 0.0);
}

}  // namespace
}  // namespace probelight::ibl
