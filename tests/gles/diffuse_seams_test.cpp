// The seam criterion on the GPU's diffuse map, and the blind spot hit
// exactly, on maps made the kiosk's way (EnvironmentMaps::updateReflection +
// updateDiffuse) from frames the simulator renders.
//
// "Seams. The largest jump across a cube-face edge of the diffuse map is no
// larger than the jump between neighbouring texels inside a face."
// Across an edge, each edge texel is paired with the texel on another face
// whose centre direction is nearest to the edge texel's centre stepped one
// texel outward (the face's s/t formula extended past the edge, then
// normalised): that is the texel a seamless sampler would blend with. Inside,
// every horizontal and vertical pair of a face. A jump is the largest
// per-channel |difference| in linear camera units.
// Both storage paths: half floats, and 8-bit sRGB (withoutExtensions()).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gles_test_support.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

struct World {
  std::string name;
  std::string environment;
  bool lamp = false;
};

std::vector<World> worlds() {
  return {{"studio", "studio"},
          {"sun_sky", "sun_sky"},
          {"kerner_exr", std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/KernerEnvLatLong.exr"},
          {"stage_exr", std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/StageEnvLatLong.exr"},
          // A bright soft box on from frame 0: the sharpest light the maps see.
          {"overcast_lamp", "overcast", true}};
}

struct BuiltMaps {
  ibl::CubeMapRGB reflection;
  std::vector<float> reflection_alpha;
  ibl::CubeMapRGB diffuse;
  std::vector<float> diffuse_alpha;
  ibl::MirrorBallView view;
};

// Frame 0 of the default (orbit) camera in `world`, the maps made from it
// with the true pose (the pose's own error is not what is tested here).
bool buildMaps(const World& world, bool force_8bit, BuiltMaps& out, std::string& error) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.environment = world.environment;
  if (world.lamp) scene.lighting.lamp_on_frame = 0;
  const sim::World sim_world(scene);
  ImageRGB8 image;
  FrameTruth truth;
  sim_world.render(0, image, truth);
  if (!truth.probe_fully_visible) {
    error = "ball not fully visible in the simulated frame";
    return false;
  }
  out.view = ibl::MirrorBallView{scene.camera, truth.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  passes::CameraFrameTexture frame;
  passes::EnvironmentMaps maps;
  if (!frame.init(caps, error) || !frame.upload(image, error) || !maps.init(caps, {}, error)) return false;
  if (force_8bit != (maps.storage() == passes::CubeStorage::kSrgb8)) {
    error = "storage is not the one asked for: " + maps.storageDescription();
    return false;
  }
  if (!maps.updateReflection(frame, out.view, scene.rig.probe_reflectance, error) || !maps.updateDiffuse(error))
    return false;
  auto reflection = maps.readReflection(error, &out.reflection_alpha);
  auto diffuse = maps.readDiffuse(error, &out.diffuse_alpha);
  if (!reflection || !diffuse) return false;
  out.reflection = std::move(*reflection);
  out.diffuse = std::move(*diffuse);
  return true;
}

float jump(const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 d = glm::abs(a - b);
  return std::max({d.r, d.g, d.b});
}

struct SeamMeasure {
  float across = 0.0f;  // largest jump over the 12 edges
  float inside = 0.0f;  // largest jump between neighbours within a face
  int pairs_across = 0;
  int faces_met = 0;  // bitmask check: each face pairs with its four neighbours
};

SeamMeasure measureSeams(const ibl::CubeMapRGB& map) {
  const int n = map.face_size;
  SeamMeasure m;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        if (x + 1 < n) m.inside = std::max(m.inside, jump(map.texel(face, x, y), map.texel(face, x + 1, y)));
        if (y + 1 < n) m.inside = std::max(m.inside, jump(map.texel(face, x, y), map.texel(face, x, y + 1)));
      }

  // Every texel centre direction, for the nearest-centre search.
  std::vector<glm::dvec3> centres;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) centres.push_back(ibl::cubeTexelCenterDirection(face, x, y, n));

  std::vector<int> neighbours_of_face(ibl::kCubeFaceCount, 0);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const int steps[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
        for (const auto& step : steps) {
          const int nx = x + step[0];
          const int ny = y + step[1];
          if (nx >= 0 && nx < n && ny >= 0 && ny < n) continue;  // not across an edge
          // cubeCoordToDirection is linear in (s, t) before normalising, so
          // s or t just past [0, 1] is the face's plane extended.
          const glm::dvec3 stepped = ibl::cubeCoordToDirection({face, (nx + 0.5) / n, (ny + 0.5) / n});
          int best = -1;
          double best_dot = -2.0;
          for (size_t i = 0; i < centres.size(); ++i) {
            if (static_cast<int>(i) / (n * n) == face) continue;
            const double d = glm::dot(centres[i], stepped);
            if (d > best_dot) {
              best_dot = d;
              best = static_cast<int>(i);
            }
          }
          const int other_face = best / (n * n);
          const int ox = best % n;
          const int oy = (best / n) % n;
          neighbours_of_face[face] |= 1 << other_face;
          m.across = std::max(m.across, jump(map.texel(face, x, y), map.texel(other_face, ox, oy)));
          ++m.pairs_across;
        }
      }
    }
  }
  // Sanity of the pairing: each face meets exactly the four faces that are
  // not itself or its opposite (GL order: +X -X +Y -Y +Z -Z).
  m.faces_met = 1;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    const int opposite = face ^ 1;
    const int expected = 0x3F & ~(1 << face) & ~(1 << opposite);
    if (neighbours_of_face[face] != expected) m.faces_met = 0;
  }
  return m;
}

class DiffuseSeams : public test::GpuTest, public ::testing::WithParamInterface<bool> {};

TEST_P(DiffuseSeams, JumpAcrossFaceEdgesIsNoLargerThanInsideFaces) {
  const bool force_8bit = GetParam();
  if (!force_8bit && !test::sharedCapabilities().canRenderHalfFloat())
    GTEST_SKIP() << "this context renders no half floats: " << test::sharedCapabilities().halfFloatRoute();
  for (const World& world : worlds()) {
    BuiltMaps maps;
    std::string error;
    ASSERT_TRUE(buildMaps(world, force_8bit, maps, error)) << world.name << ": " << error;
    ASSERT_TRUE(test::allFinite(maps.diffuse)) << world.name;
    const SeamMeasure m = measureSeams(maps.diffuse);
    const int n = maps.diffuse.face_size;
    EXPECT_EQ(m.pairs_across, 6 * 4 * n) << world.name;
    EXPECT_EQ(m.faces_met, 1) << world.name << ": the edge pairing is wrong";
    EXPECT_GT(m.inside, 0.0f) << world.name << ": a flat map would make the check vacuous";
    std::printf("[ seams ] %-14s %-5s across %.5f  inside %.5f  (ratio %.2f)\n", world.name.c_str(),
                force_8bit ? "8-bit" : "half", m.across, m.inside, m.across / m.inside);
    // The criterion, as stated: no tolerance. In 8 bits both sides
    // are quantised the same way (one level of the sRGB encoding), so the
    // rounding cannot favour one side.
    EXPECT_LE(m.across, m.inside) << world.name;
  }
}

// The check can fail: a map whose faces are each uniform but different has
// no jump inside and a jump across every edge.
TEST(DiffuseSeamsMeasure, SeesASeam) {
  ibl::CubeMapRGB map(8);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (auto& t : map.faces[face]) t = glm::vec3(0.1f * face);
  const SeamMeasure m = measureSeams(map);
  EXPECT_EQ(m.inside, 0.0f);
  EXPECT_GT(m.across, 0.05f);
  EXPECT_EQ(m.faces_met, 1);
}

INSTANTIATE_TEST_SUITE_P(Storage, DiffuseSeams, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) { return info.param ? "rgba8" : "half_float"; });

// The blind spot exactly: r = -v, straight behind the ball away from the
// camera. The CPU mapping has no pixel there, the GPU reflection map's alpha
// is 0 at the texel holding that direction, and the diffuse map is finite
// and filled there (the cosine passes divide by the blurred validity).
class BlindSpot : public test::GpuTest, public ::testing::WithParamInterface<bool> {};

TEST_P(BlindSpot, ReflectionAlphaIsZeroAndDiffuseStaysFilled) {
  if (!GetParam() && !test::sharedCapabilities().canRenderHalfFloat())
    GTEST_SKIP() << "this context renders no half floats: " << test::sharedCapabilities().halfFloatRoute();
  BuiltMaps maps;
  std::string error;
  ASSERT_TRUE(buildMaps(worlds()[0], GetParam(), maps, error)) << error;
  const glm::dvec3 away =
      glm::normalize(maps.view.center_w - maps.view.pose.cameraCenterWorld());  // r = -v
  EXPECT_FALSE(ibl::reflectedDirectionToPixel(maps.view, away).has_value());

  const int n = maps.reflection.face_size;
  const ibl::CubeTexelCoord c = ibl::directionToCubeCoord(away);
  const int x = std::clamp(static_cast<int>(c.s * n), 0, n - 1);
  const int y = std::clamp(static_cast<int>(c.t * n), 0, n - 1);
  // The blind cone's half-angle is about the ball's angular radius seen from
  // the camera (0.03 m at ~0.6 m: ~2.9 deg), while a 64^2 texel's centre is
  // at most ~1 deg from any direction it holds: the texel is fully blind.
  EXPECT_FALSE(ibl::reflectedDirectionToPixel(maps.view, ibl::cubeTexelCenterDirection(c.face, x, y, n)).has_value());
  const float alpha = maps.reflection_alpha[static_cast<size_t>(c.face * n * n + y * n + x)];
  EXPECT_EQ(alpha, 0.0f);
  EXPECT_EQ(maps.reflection.texel(c.face, x, y), glm::vec3(0.0f));  // unknown, stored as 0

  // Diffuse: every texel finite, and the one facing the blind spot filled.
  ASSERT_TRUE(test::allFinite(maps.diffuse));
  const int m = maps.diffuse.face_size;
  const ibl::CubeTexelCoord d = ibl::directionToCubeCoord(away);
  const int dx = std::clamp(static_cast<int>(d.s * m), 0, m - 1);
  const int dy = std::clamp(static_cast<int>(d.t * m), 0, m - 1);
  const glm::vec3 filled = maps.diffuse.texel(d.face, dx, dy);
  EXPECT_GT(std::min({filled.r, filled.g, filled.b}), 0.0f);
  // Coverage there: the blind cone is ~0.3% of the hemisphere's cosine
  // weight, so alpha stays near 1; anything above 0.9 says "filled".
  EXPECT_GT(maps.diffuse_alpha[static_cast<size_t>(d.face * m * m + dy * m + dx)], 0.9f);
  for (float a : maps.diffuse_alpha) ASSERT_TRUE(std::isfinite(a) && a > 0.0f);
}

INSTANTIATE_TEST_SUITE_P(Storage, BlindSpot, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) { return info.param ? "rgba8" : "half_float"; });

}  // namespace
}  // namespace probelight
