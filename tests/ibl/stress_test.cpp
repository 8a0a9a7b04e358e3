// Stress cases of the ibl entry points: NaN, Inf and zero in every float
// input (directions, poses, calibrations, map texels), and the blind spot hit
// exactly. Frames are 8-bit and cannot carry NaN, but poses and directions
// can (a degenerate pose solve, a zero vector normalised). Each must give a
// defined answer: an empty optional, an invalid flag, or zero; never a crash,
// an out-of-bounds index, or a NaN that looks like a result.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "ibl/camera_projection.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_outline.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

using testing::kioskBallView;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

bool finite(const glm::dvec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Vectors with one bad component in each position, plus all-bad and zero.
std::vector<glm::dvec3> badVectors() {
  std::vector<glm::dvec3> out;
  for (double bad : {kNaN, kInf, -kInf}) {
    for (int i = 0; i < 3; ++i) {
      glm::dvec3 v(0.3, -0.5, 0.8);
      v[i] = bad;
      out.push_back(v);
    }
    out.push_back(glm::dvec3(bad));
  }
  out.push_back(glm::dvec3(0.0));
  return out;
}

std::string describe(const glm::dvec3& v) {
  return "(" + std::to_string(v.x) + ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + ")";
}

CubeMapRGB rampMap(int n) {
  CubeMapRGB map(n);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) map.texel(face, x, y) = glm::vec3(0.2f + 0.1f * face, 0.01f * x, 0.01f * y);
  return map;
}

TEST(IblStress, CubeLookupsOfBadDirectionsAreDefined) {
  const CubeMapRGB map = rampMap(8);
  for (const glm::dvec3& d : badVectors()) {
    const CubeTexelCoord c = directionToCubeCoord(d);
    // Before the guard NaN came out as face -X with s = t = NaN, which the
    // samplers cast to int (undefined behaviour).
    EXPECT_EQ(c.face, 0) << describe(d);
    EXPECT_EQ(c.s, 0.5) << describe(d);
    EXPECT_EQ(c.t, 0.5) << describe(d);
    EXPECT_EQ(map.sampleNearest(d), glm::vec3(0.0f)) << describe(d);
    EXPECT_EQ(map.sampleBilinear(d), glm::vec3(0.0f)) << describe(d);
  }
  // A huge but finite direction still has its face (only the ratio matters).
  const CubeTexelCoord big = directionToCubeCoord({1e300, 1e299, -1e299});
  EXPECT_EQ(big.face, 0);
  EXPECT_TRUE(std::isfinite(big.s) && std::isfinite(big.t));
  EXPECT_EQ(CubeMapRGB(0).sampleBilinear({0, 0, 1}), glm::vec3(0.0f));  // empty map: no texel to read
}

TEST(IblStress, MirrorBallMappingOfBadInputIsEmpty) {
  const MirrorBallView good = kioskBallView(0.5, {320.0, 240.0});
  for (const glm::dvec3& d : badVectors())
    EXPECT_FALSE(reflectedDirectionToPixel(good, d).has_value()) << describe(d);

  // A NaN or Inf anywhere in the view: pose, ball, calibration.
  std::vector<std::pair<std::string, MirrorBallView>> bad_views;
  for (double bad : {kNaN, kInf}) {
    MirrorBallView v = good;
    v.pose.R_cam_from_world[1][2] = bad;
    bad_views.push_back({"rotation", v});
    v = good;
    v.pose.t_cam_from_world.z = bad;
    bad_views.push_back({"translation", v});
    v = good;
    v.center_w.x = bad;
    bad_views.push_back({"ball centre", v});
    v = good;
    v.radius_m = bad;
    bad_views.push_back({"ball radius", v});
    v = good;
    v.camera.fx_px = bad;
    bad_views.push_back({"fx", v});
    v = good;
    v.camera.distortion[0] = bad;
    bad_views.push_back({"k1", v});
  }
  const glm::dvec3 upward(0.1, 0.2, 1.0);
  for (const auto& [name, view] : bad_views) {
    const std::optional<glm::dvec2> pixel = reflectedDirectionToPixel(view, upward);
    EXPECT_TRUE(!pixel || finite(*pixel)) << name;
    const std::optional<glm::dvec3> reflected = pixelToReflectedDirection(view, {320.0, 240.0});
    EXPECT_TRUE(!reflected || finite(*reflected)) << name;
  }
  // The good view does give answers, so the checks above are not vacuous.
  ASSERT_TRUE(reflectedDirectionToPixel(good, upward).has_value());
  for (const glm::dvec2& pixel : {glm::dvec2(kNaN, 240.0), glm::dvec2(320.0, kInf), glm::dvec2(-kInf, kNaN)})
    EXPECT_FALSE(pixelToReflectedDirection(good, pixel).has_value()) << pixel.x << ", " << pixel.y;
}

TEST(IblStress, BlindSpotExactlyBehindTheBallIsEmpty) {
  for (const glm::dvec2 ball_px : {glm::dvec2(320.0, 240.0), glm::dvec2(590.0, 80.0), glm::dvec2(60.0, 420.0)}) {
    const MirrorBallView view = kioskBallView(0.4, ball_px);
    const glm::dvec3 to_camera = view.pose.cameraCenterWorld() - view.center_w;
    // r = -v exactly: the seed's bisector normalize(v) + r is exactly zero.
    EXPECT_FALSE(reflectedDirectionToPixel(view, -to_camera).has_value());
    EXPECT_FALSE(reflectedDirectionToPixel(view, -glm::normalize(to_camera)).has_value());
    // A hair off the blind spot: either no pixel or one on the ball's image
    // (within its outline plus a pixel), never NaN or a pixel elsewhere.
    const ProbeOutline outline = computeProbeOutline(view);
    ASSERT_TRUE(outline.valid);
    const glm::dvec3 side = glm::normalize(glm::cross(to_camera, glm::dvec3(0, 0, 1)));
    for (double tilt : {1e-12, 1e-9, 1e-6, 1e-3}) {
      const std::optional<glm::dvec2> pixel =
          reflectedDirectionToPixel(view, -glm::normalize(to_camera) + tilt * side);
      if (!pixel) continue;
      EXPECT_TRUE(finite(*pixel)) << tilt;
      EXPECT_LE(glm::length(*pixel - outline.center_px), outline.radius_px * 1.1 + 1.0) << tilt;
    }
  }
}

TEST(IblStress, ProbeOutlineOfBadViewIsInvalid) {
  const MirrorBallView good = kioskBallView(0.5, {320.0, 240.0});
  ASSERT_TRUE(computeProbeOutline(good).valid);
  for (double bad : {kNaN, kInf, -kInf}) {
    for (int field = 0; field < 7; ++field) {
      MirrorBallView v = good;
      switch (field) {
        case 0: v.pose.R_cam_from_world[0][0] = bad; break;
        case 1: v.pose.t_cam_from_world.x = bad; break;
        case 2: v.center_w.z = bad; break;
        case 3: v.radius_m = bad; break;
        case 4: v.camera.fx_px = bad; break;
        case 5: v.camera.cy_px = bad; break;
        default: v.camera.distortion[4] = bad; break;
      }
      const ProbeOutline outline = computeProbeOutline(v);
      // Before the guard a NaN pose gave valid = true with a NaN centre.
      EXPECT_FALSE(outline.valid) << "field " << field << " = " << bad;
      EXPECT_FALSE(outline.fully_in_image) << "field " << field << " = " << bad;
    }
  }
}

TEST(IblStress, ProjectToPixelOfBadPointIsNonFiniteNotACrash) {
  // Documented: non-finite in, non-finite out (zero would be a real pixel);
  // the callers above turn it into "no pixel".
  const CameraIntrinsics camera = testing::kioskCamera();
  for (const glm::dvec3& p : badVectors()) {
    const glm::dvec2 pixel = projectToPixel(camera, p);
    // The one exception is the limit itself: finite x, y at z = +-Inf is a
    // point infinitely far along the axis, which images at the principal point.
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isinf(p.z)) {
      EXPECT_EQ(pixel, glm::dvec2(camera.cx_px, camera.cy_px)) << describe(p);
      continue;
    }
    EXPECT_FALSE(finite(pixel)) << describe(p);
  }
  EXPECT_TRUE(finite(projectToPixel(camera, {0.01, 0.02, 0.5})));
  EXPECT_FALSE(finite(pixelToCameraRay(camera, {kNaN, 100.0})));
}

TEST(IblStress, ShProjectionAndIrradianceIgnoreBadTexelsAndNormals) {
  const int n = 8;
  CubeMapRGB map(n);
  for (auto& face : map.faces)
    for (auto& t : face) t = glm::vec3(0.5f);  // uniform radiance 0.5: E = pi * 0.5 everywhere
  const SH9RGB clean = projectToSH9(map);
  // Poison a few texels: they count as unseen, so a uniform map stays uniform.
  map.texel(0, 3, 3) = glm::vec3(std::numeric_limits<float>::quiet_NaN());
  map.texel(2, 0, 7).g = std::numeric_limits<float>::infinity();
  map.texel(5, 4, 1).b = -std::numeric_limits<float>::infinity();
  const SH9RGB sh = projectToSH9(map);
  for (int k = 0; k < kSH9Count; ++k) {
    ASSERT_TRUE(finite(sh.coefficients[k])) << k;
    // Leaving 3 of 384 texels out of a uniform map changes nothing but
    // round-off: the Gram solve refits the constant exactly.
    EXPECT_NEAR(sh.coefficients[k].r, clean.coefficients[k].r, 1e-9) << k;
  }
  const glm::dvec3 e = irradianceFromSH9(sh, {0.0, 0.0, 1.0});
  EXPECT_NEAR(e.r, M_PI * 0.5, 1e-3 * M_PI);  // R&H's 9 terms are exact for a constant, up to their rounded constants

  // Bad normals: zero, not NaN.
  for (const glm::dvec3& normal : badVectors()) {
    EXPECT_EQ(irradianceFromSH9(sh, normal), glm::dvec3(0.0)) << describe(normal);
    EXPECT_EQ(irradianceFromCubeMap(map, normal), glm::dvec3(0.0)) << describe(normal);
  }
  // The CPU irradiance skips the poisoned texels too (they add nothing).
  const glm::dvec3 e_cube = irradianceFromCubeMap(map, {1.0, 0.0, 0.0});
  EXPECT_TRUE(finite(e_cube));
  EXPECT_NEAR(e_cube.r, M_PI * 0.5, 0.02 * M_PI * 0.5);  // 8^2 faces: midpoint quadrature within ~1%

  // A validity of the wrong length cannot be matched to texels: zero, and no
  // out-of-bounds read (before the guard it read past the vector's end).
  const std::vector<float> short_validity(10, 1.0f);
  const SH9RGB none = projectToSH9(map, &short_validity);
  for (int k = 0; k < kSH9Count; ++k) EXPECT_EQ(none.coefficients[k], glm::dvec3(0.0)) << k;
  // NaN validity counts as unseen; all unseen: zero coefficients.
  const std::vector<float> nan_validity(static_cast<size_t>(6 * n * n), std::numeric_limits<float>::quiet_NaN());
  const SH9RGB unseen = projectToSH9(map, &nan_validity);
  for (int k = 0; k < kSH9Count; ++k) EXPECT_EQ(unseen.coefficients[k], glm::dvec3(0.0)) << k;
}

}  // namespace
}  // namespace probelight::ibl
