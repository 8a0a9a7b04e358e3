// stages/probe_merge: the probe over views in the maps' units, following the
// camera's exposure, with the 8-bit part for the live maps and the measured
// highlights for the fit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../ibl/ibl_test_helpers.hpp"
#include "ibl/cube_map.hpp"
#include "stages/probe_merge.hpp"

namespace probelight {
namespace {

constexpr int kFace = 16;

// A kiosk-like view of the rig's 3 cm ball 0.5 m away.
ibl::MirrorBallView kioskView() { return ibl::testing::kioskBallView(0.5, {330.0, 250.0}); }

RigGeometry rig() {
  RigGeometry rig;
  rig.probe_reflectance = 0.6;
  return rig;
}

ibl::CubeMapRGB uniformMap(float level) {
  ibl::CubeMapRGB map(kFace);
  for (auto& face : map.faces)
    for (glm::vec3& texel : face) texel = glm::vec3(level);
  return map;
}

// The seen texels' largest and smallest luminance.
std::pair<float, float> seenRange(const ibl::CubeMapRGB& map, const std::vector<float>& validity) {
  float low = INFINITY, high = 0.0f;
  const std::size_t per_face = static_cast<std::size_t>(kFace) * kFace;
  for (std::size_t i = 0; i < validity.size(); ++i) {
    if (validity[i] == 0.0f) continue;
    const glm::vec3& v = map.faces[i / per_face][i % per_face];
    low = std::min(low, std::max({v.r, v.g, v.b}));
    high = std::max(high, std::max({v.r, v.g, v.b}));
  }
  return {low, high};
}

TEST(ProbeMerge, FollowsTheCameraExposureAndIgnoresExposuresItCannotKnow) {
  ProbeMerge probe(ibl::CameraTransfer{}, rig(), kFace);
  EXPECT_TRUE(probe.empty());
  EXPECT_EQ(probe.toProbeExposure(1000.0), 1.0) << "no exposure known yet";
  probe.followExposure(1000.0);  // names the units: nothing to scale
  const ProbeViewCounts counts = probe.addView(kioskView(), uniformMap(0.3f), nullptr, nullptr, 1.0, nullptr);
  EXPECT_GT(counts.merge.seen, 0);
  EXPECT_EQ(counts.merge.first, counts.merge.seen);
  EXPECT_EQ(counts.texels_from_frame_around_ball, 0);
  const std::vector<float> validity = probe.validity();
  auto [low, high] = seenRange(probe.liveMap(), validity);
  EXPECT_FLOAT_EQ(low, 0.3f);
  EXPECT_FLOAT_EQ(high, 0.3f);
  // Twice the exposure: camera-linear values double.
  probe.followExposure(2000.0);
  std::tie(low, high) = seenRange(probe.hdrMap(), validity);
  EXPECT_FLOAT_EQ(low, 0.6f);
  EXPECT_FLOAT_EQ(high, 0.6f);
  EXPECT_EQ(probe.exposure(), 2000.0);
  // A view at half the probe's exposure is doubled to join it.
  EXPECT_DOUBLE_EQ(probe.toProbeExposure(1000.0), 2.0);
  EXPECT_EQ(probe.toProbeExposure(0.0), 1.0);
  EXPECT_EQ(probe.toProbeExposure(NAN), 1.0);
  // What a source cannot say moves nothing.
  for (double unknown : {0.0, -5.0, static_cast<double>(NAN), static_cast<double>(INFINITY)}) probe.followExposure(unknown);
  EXPECT_EQ(probe.exposure(), 2000.0);
  std::tie(low, high) = seenRange(probe.hdrMap(), validity);
  EXPECT_FLOAT_EQ(high, 0.6f);
}

// The white balance's red and blue gains move the probe's red and blue as
// the exposure moves all three; the first known gains only name the units,
// and gains a source cannot say move nothing.
TEST(ProbeMerge, FollowsTheWhiteBalancePerChannel) {
  ProbeMerge probe(ibl::CameraTransfer{}, rig(), kFace);
  probe.followWhiteBalance(2.0, 1.5);  // names the units
  probe.addView(kioskView(), uniformMap(0.3f), nullptr, nullptr, 1.0, nullptr);
  const std::vector<float> validity = probe.validity();
  auto texelAt = [&](const ibl::CubeMapRGB& map) {
    for (std::size_t i = 0; i < validity.size(); ++i)
      if (validity[i] != 0.0f) return map.faces[i / (kFace * kFace)][i % (kFace * kFace)];
    return glm::vec3(-1.0f);
  };
  probe.followWhiteBalance(3.0, 0.75);  // red x1.5, blue x0.5
  glm::vec3 texel = texelAt(probe.hdrMap());
  EXPECT_FLOAT_EQ(texel.r, 0.45f);
  EXPECT_FLOAT_EQ(texel.g, 0.3f);
  EXPECT_FLOAT_EQ(texel.b, 0.15f);
  for (double unknown : {0.0, -1.0, static_cast<double>(NAN)}) probe.followWhiteBalance(unknown, unknown);
  texel = texelAt(probe.hdrMap());
  EXPECT_FLOAT_EQ(texel.r, 0.45f);
  EXPECT_FLOAT_EQ(texel.b, 0.15f);
  // The live map's clip can be moved per channel (the fit frame's clip in
  // today's units): each channel stops at its own.
  const glm::vec3 clip_scale(0.4f / static_cast<float>(probe.clipLevel()), 1.0f, 0.1f / static_cast<float>(probe.clipLevel()));
  texel = texelAt(probe.liveMap(clip_scale));
  EXPECT_FLOAT_EQ(texel.r, 0.4f);
  EXPECT_FLOAT_EQ(texel.g, 0.3f);
  EXPECT_FLOAT_EQ(texel.b, 0.1f);
}

TEST(ProbeMerge, TheLiveMapStopsAtTheClipAndTheFitGetsTheMeasuredHighlights) {
  ProbeMerge probe(ibl::CameraTransfer{}, rig(), kFace);
  const float clip = static_cast<float>(probe.clipLevel());
  // sRGB's clip code 250 through a 0.6 reflectance: 0.957 / 0.6.
  EXPECT_NEAR(clip, ibl::srgbToLinear(250.0 / 255.0) / 0.6, 1e-6);
  // An 8-bit view whose every texel clipped: lower bounds only.
  probe.addView(kioskView(), uniformMap(clip), nullptr, nullptr, 1.0, nullptr);
  EXPECT_FALSE(probe.holdsAboveClip()) << "a clipped sample says only 'at least the clip'";
  // A bracket of the same view measured 5 x the clip everywhere (no flag
  // still clipped): it raises every bound.
  const std::vector<std::uint8_t> none_clipped(6u * kFace * kFace, 0);
  const ProbeViewCounts bracket =
      probe.addView(kioskView(), uniformMap(5.0f * clip), nullptr, &none_clipped, 1.0, nullptr);
  EXPECT_GT(bracket.merge.seen, 0);
  EXPECT_TRUE(probe.holdsAboveClip());
  const std::vector<float> validity = probe.validity();
  auto [low, high] = seenRange(probe.hdrMap(), validity);
  EXPECT_NEAR(low, 5.0f * clip, 1e-4f * clip);
  EXPECT_NEAR(high, 5.0f * clip, 1e-4f * clip);
  std::tie(low, high) = seenRange(probe.liveMap(), validity);
  EXPECT_FLOAT_EQ(high, clip) << "the live maps hold what 8 bits show; the rest is the clipped lights'";
  // A later 8-bit view that clips there again is consistent with the
  // measurement and keeps it.
  const ProbeViewCounts again = probe.addView(kioskView(), uniformMap(clip), nullptr, nullptr, 1.0, nullptr);
  EXPECT_EQ(again.merge.kept, again.merge.seen);
  EXPECT_TRUE(probe.holdsAboveClip());
}

TEST(ProbeMerge, AStoredProbeOfAnotherSizeChangesNothing) {
  ProbeMerge probe(ibl::CameraTransfer{}, rig(), kFace);
  probe.followExposure(500.0);
  probe.addView(kioskView(), uniformMap(0.2f), nullptr, nullptr, 1.0, nullptr);
  const std::vector<glm::vec4> before = probe.accumulator().texels();
  std::string error;
  EXPECT_FALSE(probe.restore(std::vector<glm::vec4>(6u * 8u * 8u, glm::vec4(1.0f)), 900.0, error));
  EXPECT_NE(error.find("texels"), std::string::npos) << error;
  EXPECT_EQ(probe.accumulator().texels(), before);
  EXPECT_EQ(probe.exposure(), 500.0);
  // One of its own size is taken whole, with its exposure.
  std::vector<glm::vec4> saved(before.size(), glm::vec4(0.4f, 0.4f, 0.4f, 100.0f));
  ASSERT_TRUE(probe.restore(saved, 900.0, error)) << error;
  EXPECT_EQ(probe.exposure(), 900.0);
  EXPECT_EQ(probe.accumulator().texels(), saved);
}

}  // namespace
}  // namespace probelight
