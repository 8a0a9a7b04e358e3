// The last fit's clipped lights followed between fits: each scaled by the
// share of its texels still clipped now over the share clipped at the fit
// (the exposure and white balance since the fit are the lights stage's:
// stages/frame_response.hpp). Synthetic 4^2 maps, so every expected share
// follows from the rule by hand.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "ibl/cube_map.hpp"
#include "stages/clipped_light_follower.hpp"

namespace probelight {
namespace {

constexpr double kClip = 1.0;  // a texel at or above this clipped

// A light of four texels on face +Z (indices 0..3), a quarter of its energy
// each, and a second one of two texels on face -Z, 0.75 and 0.25.
std::vector<ibl::ClippedLight> twoLights() {
  ibl::ClippedLight sun;
  sun.irradiance_rgb = glm::dvec3(4.0);
  sun.texels = {4 * 16 + 0, 4 * 16 + 1, 4 * 16 + 2, 4 * 16 + 3};
  sun.texel_share = {0.25f, 0.25f, 0.25f, 0.25f};
  ibl::ClippedLight lamp;
  lamp.irradiance_rgb = glm::dvec3(1.0);
  lamp.texels = {5 * 16 + 0, 5 * 16 + 1};
  lamp.texel_share = {0.75f, 0.25f};
  return {sun, lamp};
}

// A 4^2 map with the given texels (face * 16 + index) at the clip level, the
// rest at a tenth of it.
ibl::CubeMapRGB mapClippedAt(const std::vector<int>& clipped) {
  ibl::CubeMapRGB map(4);
  for (auto& face : map.faces)
    for (glm::vec3& texel : face) texel = glm::vec3(0.1f);
  for (int t : clipped) map.faces[t / 16][t % 16] = glm::vec3(0.2f, static_cast<float>(kClip), 0.3f);
  return map;
}

TEST(ClippedLightFollower, AStillSceneKeepsEveryLightWhole) {
  ClippedLightFollower follower;
  const ibl::CubeMapRGB at_fit = mapClippedAt({64, 65, 66, 67, 80, 81});
  follower.follow(twoLights(), at_fit, kClip, 8000.0);
  ASSERT_EQ(follower.shareAtFit().size(), 2u);
  EXPECT_DOUBLE_EQ(follower.shareAtFit()[0], 1.0);
  EXPECT_DOUBLE_EQ(follower.shareAtFit()[1], 1.0);
  const std::vector<double> scale = follower.sharesFor(at_fit, kClip);
  ASSERT_EQ(scale.size(), 2u);
  EXPECT_DOUBLE_EQ(scale[0], 1.0);
  EXPECT_DOUBLE_EQ(scale[1], 1.0);
}

TEST(ClippedLightFollower, ALightThatLeavesItsTexelsFadesByTheirShare) {
  ClippedLightFollower follower;
  follower.follow(twoLights(), mapClippedAt({64, 65, 66, 67, 80, 81}), kClip, 8000.0);
  // Half the sun's texels no longer clip (a cloud over half of it); the
  // lamp's larger texel is dark (0.25 of it is left).
  const std::vector<double> scale = follower.sharesFor(mapClippedAt({64, 65, 81}), kClip);
  EXPECT_DOUBLE_EQ(scale[0], 0.5);
  EXPECT_NEAR(scale[1], 0.25, 1e-7);  // shares are floats
  // Switched off altogether.
  EXPECT_DOUBLE_EQ(follower.sharesFor(mapClippedAt({}), kClip)[1], 0.0);
}

TEST(ClippedLightFollower, NeverAboveWhatWasMeasured) {
  ClippedLightFollower follower;
  // At the fit only half the sun clipped (its edge was in the map's range).
  follower.follow(twoLights(), mapClippedAt({64, 65, 80, 81}), kClip, 8000.0);
  EXPECT_DOUBLE_EQ(follower.shareAtFit()[0], 0.5);
  // Now all of it clips (auto exposure lengthened, say): the sun is no
  // brighter for that, so the share is capped at the fit's.
  const std::vector<double> share = follower.sharesFor(mapClippedAt({64, 65, 66, 67, 80, 81}), kClip);
  EXPECT_DOUBLE_EQ(share[0], 1.0);
  EXPECT_DOUBLE_EQ(share[1], 1.0);
}

TEST(ClippedLightFollower, ALightNothingOfWhichClippedAtTheFitCannotBeFollowed) {
  ClippedLightFollower follower;
  // Stored lighting from an older file: no shares. Each light keeps share 1.
  follower.restore(twoLights(), {}, 4000.0);
  ASSERT_EQ(follower.shareAtFit().size(), 2u);
  EXPECT_DOUBLE_EQ(follower.shareAtFit()[1], 0.0);
  EXPECT_DOUBLE_EQ(follower.exposureAtFit(), 4000.0);
  const std::vector<double> share = follower.sharesFor(mapClippedAt({}), kClip);
  EXPECT_DOUBLE_EQ(share[0], 1.0);
  EXPECT_DOUBLE_EQ(share[1], 1.0);
}

// Texels a sharper view than the fit's bracket resolved (it showed them
// holding something else) leave the light: their going out of the clip
// does not dim it while the rest still clips; a light nothing of which
// clips has gone whatever was resolved; a texel that clips counts as the
// light's even where flagged.
TEST(ClippedLightFollower, TexelsASharperViewResolvedLeaveTheLightWithoutDimmingIt) {
  ClippedLightFollower follower;
  follower.follow(twoLights(), mapClippedAt({64, 65, 66, 67, 80, 81}), kClip, 8000.0);
  std::vector<std::uint8_t> resolved(6 * 16, 0);
  resolved[66] = resolved[67] = 1;  // half the sun was a smear: sky there
  // Sun: 0.5 still clips, 0.5 resolved: all of what is left of it is there.
  // Lamp: its 0.75 texel went out (not resolved), 0.25 left.
  std::vector<double> share = follower.sharesFor(mapClippedAt({64, 65, 81}), kClip, &resolved);
  EXPECT_DOUBLE_EQ(share[0], 1.0);
  EXPECT_NEAR(share[1], 0.25, 1e-7);
  // Without the flags, the same map halves the sun.
  EXPECT_DOUBLE_EQ(follower.sharesFor(mapClippedAt({64, 65, 81}), kClip)[0], 0.5);
  // One of the two still-clipping sun texels goes out unresolved: a quarter
  // of the sun's fit-time share is gone of the half that is still its.
  share = follower.sharesFor(mapClippedAt({64, 81}), kClip, &resolved);
  EXPECT_DOUBLE_EQ(share[0], 0.5);
  // Nothing of the sun clips: gone.
  EXPECT_DOUBLE_EQ(follower.sharesFor(mapClippedAt({81}), kClip, &resolved)[0], 0.0);
  // A flagged texel that clips again is the light's.
  EXPECT_DOUBLE_EQ(follower.sharesFor(mapClippedAt({64, 65, 66, 67, 81}), kClip, &resolved)[0], 1.0);
  // Flags for a map of another size are ignored.
  const std::vector<std::uint8_t> wrong_size(10, 1);
  EXPECT_DOUBLE_EQ(follower.sharesFor(mapClippedAt({64, 65, 81}), kClip, &wrong_size)[0], 0.5);
}

TEST(ClippedLightFollower, AnUnknownExposureCountsAsOne) {
  EXPECT_DOUBLE_EQ(exposureProduct(0.0, 4.0), 1.0);      // the source cannot say
  EXPECT_DOUBLE_EQ(exposureProduct(8000.0, 0.0), 8000.0);  // no gain said: 1
  EXPECT_DOUBLE_EQ(exposureProduct(8000.0, 2.0), 16000.0);
}

}  // namespace
}  // namespace probelight
