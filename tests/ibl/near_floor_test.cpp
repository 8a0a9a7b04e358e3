#include "ibl/near_floor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "ibl/metallic_roughness.hpp"

namespace probelight::ibl {
namespace {

// The default rig's ball: 3 cm, its centre 8 cm up, 12 cm along +X from the
// tag; the camera 0.6 m away on the -Y side, 40 degrees up.
NearFloorBall rigBall() {
  NearFloorBall ball;
  ball.centre_w = {0.12f, 0.0f, 0.08f};
  ball.radius_m = 0.03f;
  ball.to_eye_w = glm::normalize(glm::vec3(0.0f, -std::cos(glm::radians(40.0f)), std::sin(glm::radians(40.0f))));
  return ball;
}

// atan2 of the cross and dot products: exact near 0, where acos of a float
// dot product bottoms out at 0.02 degrees.
double angleDeg(const glm::vec3& a, const glm::vec3& b) {
  const glm::dvec3 u(a), v(b);
  return glm::degrees(std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v)));
}

TEST(NearFloor, DirectionsThatDoNotGoDownAreReadAsTheyAre) {
  for (const glm::vec3& up : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, 2, 0.3f)), glm::vec3(1, 0, 0)}) {
    const NearFloorLookup lookup = nearFloorLookup({-0.1f, 0.06f, 0.02f}, up, rigBall());
    EXPECT_FALSE(lookup.meets_ground);
    EXPECT_EQ(lookup.map_direction_w, up);
  }
}

// Where the ray meets the ground, and, with a ball of no size, the
// direction from its centre to there.
TEST(NearFloor, ADownwardRayIsReadWhereTheBallsCentreSeesItsGroundPoint) {
  NearFloorBall point_ball = rigBall();
  point_ball.radius_m = 0.0f;
  const glm::vec3 p(-0.10f, 0.06f, 0.03f);
  const glm::vec3 d = glm::normalize(glm::vec3(0.5f, -0.3f, -0.4f));
  const NearFloorLookup lookup = nearFloorLookup(p, d, point_ball);
  ASSERT_TRUE(lookup.meets_ground);
  const float t = 0.03f / (0.4f / glm::length(glm::vec3(0.5f, -0.3f, -0.4f)));
  EXPECT_NEAR(glm::length(lookup.ground_point_w - (p + t * d)), 0.0f, 1e-6f);
  EXPECT_EQ(lookup.ground_point_w.z, 0.0f);
  EXPECT_LT(angleDeg(lookup.map_direction_w, lookup.ground_point_w - point_ball.centre_w), 1e-3);
  // A point on the ground reflects the ground it stands on.
  const NearFloorLookup touching = nearFloorLookup({-0.1f, 0.06f, 0.0f}, d, point_ball);
  EXPECT_NEAR(glm::length(touching.ground_point_w - glm::vec3(-0.1f, 0.06f, 0.0f)), 0.0f, 1e-7f);
}

// The maps' direction d shows the ground from the ball's surface: the
// camera's ray mirrored at c + R normalize(d + v) leaves along d, and goes
// on to the ground point. For points all around the model's place, within
// 0.2 mm (3 fixed-point steps; the first alone is centimetres off).
TEST(NearFloor, TheBallsOwnParallaxIsUndoneByItsReflectingPoint) {
  const NearFloorBall ball = rigBall();
  double worst_m = 0.0, worst_centre_only_m = 0.0;
  for (const glm::vec3& ground : {glm::vec3(-0.10f, 0.02f, 0.0f), glm::vec3(-0.05f, 0.10f, 0.0f),
                                  glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(-0.2f, -0.1f, 0.0f), glm::vec3(0.05f, -0.05f, 0.0f)}) {
    // A surface point 2 cm above the ground looking down at `ground`.
    const glm::vec3 p = ground + glm::vec3(-0.02f, 0.01f, 0.02f);
    const NearFloorLookup lookup = nearFloorLookup(p, glm::normalize(ground - p), ball);
    ASSERT_TRUE(lookup.meets_ground);
    EXPECT_NEAR(glm::length(lookup.ground_point_w - ground), 0.0, 1e-6);
    auto landing = [&](const glm::vec3& d) {
      const glm::vec3 n = glm::normalize(d + ball.to_eye_w);
      const glm::vec3 on_ball = ball.centre_w + ball.radius_m * n;
      const glm::vec3 out = glm::reflect(-ball.to_eye_w, n);  // = d, by construction of n
      EXPECT_LT(angleDeg(out, d), 1e-3);
      return on_ball + (on_ball.z / -out.z) * out;
    };
    worst_m = std::max(worst_m, static_cast<double>(glm::length(landing(lookup.map_direction_w) - ground)));
    worst_centre_only_m = std::max(
        worst_centre_only_m, static_cast<double>(glm::length(landing(glm::normalize(ground - ball.centre_w)) - ground)));
  }
  EXPECT_LT(worst_m, 2e-4);
  EXPECT_GT(worst_centre_only_m, 0.01) << "the ball's parallax is not small at these distances";
}

// No seam at the horizon: as the ray levels out, the ground point runs off
// and the maps are read ever closer to the ray's own direction.
TEST(NearFloor, AtTheHorizonTheLookupTendsToTheRaysOwnDirection) {
  const glm::vec3 p(-0.10f, 0.06f, 0.03f);
  double previous_deg = 180.0;
  for (const float z : {-0.5f, -0.1f, -0.02f, -0.004f, -0.001f}) {
    const glm::vec3 d = glm::normalize(glm::vec3(0.6f, 0.8f, z));
    const NearFloorLookup lookup = nearFloorLookup(p, d, rigBall());
    const double deg = angleDeg(lookup.map_direction_w, d);
    EXPECT_LT(deg, previous_deg) << z;
    previous_deg = deg;
  }
  // At 0.001 the point is 20 m out (the search's end): within a degree.
  EXPECT_LT(previous_deg, 1.0);
  const NearFloorLookup far = nearFloorLookup(p, glm::normalize(glm::vec3(1.0f, 0.0f, -1e-6f)), rigBall());
  EXPECT_LE(glm::length(far.ground_point_w - p), kNearFloorMaxDistance_m + 1e-3f);
}

// The frame is trusted fully from 8 px inside its edge, linearly less to
// nothing at the edge and beyond; and only within 1.5 times its own reach
// from the axis, where the distortion still maps points in order.
TEST(NearFloor, TheCameraFrameIsReadWellInsideItsEdgeAndItsLens) {
  EXPECT_EQ(cameraFloorWeight({320.0f, 240.0f}, 640, 480), 1.0f);
  EXPECT_EQ(cameraFloorWeight({7.5f, 240.0f}, 640, 480), 1.0f);
  EXPECT_NEAR(cameraFloorWeight({3.5f, 240.0f}, 640, 480), 0.5f, 1e-6f);
  EXPECT_NEAR(cameraFloorWeight({320.0f, 479.0f - 3.5f}, 640, 480), 0.5f, 1e-6f);
  EXPECT_EQ(cameraFloorWeight({-0.5f, 240.0f}, 640, 480), 0.0f);
  EXPECT_EQ(cameraFloorWeight({700.0f, 240.0f}, 640, 480), 0.0f);
  CameraIntrinsics camera;
  camera.width_px = 640;
  camera.height_px = 480;
  camera.fx_px = camera.fy_px = 525.0;
  camera.cx_px = 319.5;
  camera.cy_px = 239.5;
  // A pinhole: the corners at (320 / 525, 240 / 525), |.|^2 = 0.5805.
  EXPECT_NEAR(cameraFloorReach2(camera), 2.25 * (320.0 * 320.0 + 240.0 * 240.0) / (525.0 * 525.0), 1e-9);
  // A barrel lens reaches further for the same corners.
  camera.distortion = {-0.28, 0.07, 0.0, 0.0, 0.0};
  EXPECT_GT(cameraFloorReach2(camera), 2.25 * (320.0 * 320.0 + 240.0 * 240.0) / (525.0 * 525.0));
}

// In the shading: a metal's downward reflection is read in the corrected
// direction and darkened by the shadow's fraction there; an upward one is
// untouched by either.
TEST(NearFloor, TheShadingReadsTheFloorThroughTheLookupAndItsShadow) {
  // A map whose colour says its direction: the lower hemisphere red by how
  // far it points along +X, the sky blue.
  CubeMapRGB map(16);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        const glm::dvec3 dir = cubeTexelCenterDirection(face, x, y, 16);
        map.faces[face][static_cast<size_t>(y) * 16 + x] =
            dir.z < 0.0 ? glm::vec3(0.5f + 0.5f * static_cast<float>(dir.x), 0.0f, 0.0f) : glm::vec3(0.0f, 0.0f, 1.0f);
      }
  const EnvironmentBrdfTable table(32, 64);
  MetallicRoughnessSurface mirror;
  mirror.base_color = glm::vec3(1.0f);
  mirror.metallic = 1.0f;
  mirror.roughness = 0.0f;
  const std::vector<double> alphas = specularRungAlphas({});
  NearFloorShading floor;
  floor.point_w = {-0.10f, 0.06f, 0.02f};
  floor.ball = rigBall();
  floor.fraction = [](const glm::vec2&) { return glm::vec3(0.25f); };
  const glm::vec3 to_eye = glm::normalize(glm::vec3(0.0f, -1.0f, 1.0f));
  // Facing down and toward +X: the reflection goes down.
  const glm::vec3 down_normal = glm::normalize(glm::vec3(0.3f, -0.5f, -0.2f));
  const glm::vec3 plain = shadeMetallicRoughness(down_normal, to_eye, mirror, map, map, {}, alphas, table, {});
  const glm::vec3 near = shadeMetallicRoughness(down_normal, to_eye, mirror, map, map, {}, alphas, table, {}, &floor);
  const glm::vec3 r = glm::reflect(-to_eye, down_normal);
  ASSERT_LT(r.z, 0.0f);
  const NearFloorLookup lookup = nearFloorLookup(floor.point_w, r, floor.ball);
  const glm::vec3 expected_ratio(0.25f * map.sampleBilinear(glm::dvec3(lookup.map_direction_w)).r /
                                 map.sampleBilinear(glm::dvec3(r)).r);
  EXPECT_NEAR(near.r / plain.r, expected_ratio.r, 1e-4f);
  // Facing up: the sky, as it was.
  const glm::vec3 up_normal = glm::normalize(glm::vec3(0.0f, -0.2f, 1.0f));
  EXPECT_EQ(shadeMetallicRoughness(up_normal, to_eye, mirror, map, map, {}, alphas, table, {}, &floor),
            shadeMetallicRoughness(up_normal, to_eye, mirror, map, map, {}, alphas, table, {}));
}

}  // namespace
}  // namespace probelight::ibl
