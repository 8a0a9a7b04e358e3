// The GPU ground shadow against its CPU reference (ibl::groundLightFraction),
// on both depth storages, in batches, and composited onto a camera frame.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/light_dome.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/object_compositor.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"

namespace probelight {
namespace {

using test::GpuTest;

glm::dvec3 direction(double azimuth_deg, double elevation_deg) {
  const double a = glm::radians(azimuth_deg), e = glm::radians(elevation_deg);
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

// A room with a lamp, as a 32^2 cube, and its 8-light dome's ground lights.
std::vector<ibl::ShadowLight> roomLights(int count = 8) {
  const glm::dvec3 lamp = direction(200.0, 35.0);
  ibl::CubeMapRGB cube(32);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const glm::dvec3 d = ibl::cubeTexelCenterDirection(face, x, y, 32);
        glm::dvec3 value = d.z < 0 ? glm::dvec3(0.1) : glm::dvec3(0.35, 0.42, 0.55) * (0.6 + 0.4 * d.z);
        if (d.z >= 0 && std::acos(std::clamp(glm::dot(d, lamp), -1.0, 1.0)) < glm::radians(6.0)) value += glm::dvec3(30.0);
        cube.texel(face, x, y) = glm::vec3(value);
      }
  ibl::LightDomeSettings settings;
  settings.light_count = count;
  return ibl::groundShadowLights(ibl::fitLightDome(cube, nullptr, settings));
}

struct ShadowComparison {
  double mean_abs = 0.0, max_abs = 0.0, p99_abs = 0.0;
};

ShadowComparison compareWithReference(const passes::GroundShadow& shadow, const std::vector<glm::vec3>& fraction,
                                const ibl::ShadowCaster& caster, const std::vector<ibl::ShadowLight>& lights) {
  ShadowComparison result;
  const int n = shadow.groundTextureSizePx();
  int count = 0;
  std::vector<double> errors;
  // Every 4th texel each way: 4096 points, each against 1024 cone samples a light.
  for (int j = 1; j < n; j += 4)
    for (int i = 1; i < n; i += 4) {
      const glm::dvec2 p = shadow.groundPointOfTexel(i, j);
      const glm::dvec3 reference = ibl::groundLightFraction(p, caster, lights, 1024);
      const glm::vec3 gpu = fraction[static_cast<std::size_t>(j) * n + i];
      const double error = std::abs(gpu.g - reference.g);
      result.mean_abs += error;
      result.max_abs = std::max(result.max_abs, error);
      errors.push_back(error);
      if (std::getenv("PROBELIGHT_SHADOW_DETAIL") && error > 0.08)
        std::printf("  (%.4f, %.4f): gpu %.3f reference %.3f\n", p.x, p.y, gpu.g, reference.g);
      ++count;
    }
  result.mean_abs /= count;
  std::sort(errors.begin(), errors.end());
  result.p99_abs = errors[errors.size() * 99 / 100];
  return result;
}

// false: this GPU's depth textures. true: the plain GLES2 path (extensions
// masked: no OES_depth_texture, so depth packed in RGBA8; mediump-declared
// shaders; 8 texture units).
class GroundShadowTest : public GpuTest, public ::testing::WithParamInterface<bool> {
 protected:
  gles::Capabilities capabilities() const {
    return GetParam() ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  }
};

// One light straight overhead, as sharp as the maps allow: the shadow of a
// sphere is the disc under it, and all of the light.
TEST_P(GroundShadowTest, OverheadLightCastsTheDiscUnderTheSphere) {
  const bool packed = GetParam();
  if (!packed && !test::sharedCapabilities().depth_texture) GTEST_SKIP() << "no OES_depth_texture here";
  passes::GroundShadow shadow;
  std::string error;
  ASSERT_TRUE(shadow.init(capabilities(), {}, error)) << error;
  ASSERT_EQ(shadow.packedDepth(), packed);
  ibl::ShadowLight light;
  light.direction_w = {0, 0, 1};
  light.share_rgb = glm::dvec3(1.0);
  light.cone_radius_rad = 0.0;
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.04;
  ASSERT_TRUE(shadow.update({light}, sphere, error)) << error;
  EXPECT_EQ(shadow.shadowPassesLastUpdate(), 1);
  const auto fraction = shadow.readFraction(error);
  ASSERT_TRUE(fraction) << error;
  const int n = shadow.groundTextureSizePx();
  // The region is the sphere's own footprint (an overhead light casts no
  // farther): 1.05 r, whose corners reach 1.48 r. One ground texel is 2 * 1.05 r / 256; a shadow-map
  // texel 2 * 1.04 r / 256; the PCF's smallest radius one texel: so the
  // edge is sharp to ~2 texels of either, under 0.05 r. Inside 0.9 r: dark;
  // outside 1.1 r: lit.
  int checked_inside = 0, checked_outside = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double distance = glm::length(shadow.groundPointOfTexel(i, j) - glm::dvec2(0.0)) / sphere.radius_m;
      const float value = (*fraction)[static_cast<std::size_t>(j) * n + i].g;
      if (distance < 0.9) {
        EXPECT_LE(value, 1.5f / 255.0f) << i << "," << j;
        ++checked_inside;
      } else if (distance > 1.1) {
        EXPECT_GE(value, 253.5f / 255.0f) << i << "," << j;
        ++checked_outside;
      }
    }
  EXPECT_GT(checked_inside, 1000);
  EXPECT_GT(checked_outside, 1000) << "the square's corners lie beyond the disc";
}

// The whole dome: 8 soft lights of different widths, against the CPU model.
TEST_P(GroundShadowTest, DomeShadowMatchesTheReferenceForASphereAndABox) {
  const bool packed = GetParam();
  if (!packed && !test::sharedCapabilities().depth_texture) GTEST_SKIP() << "no OES_depth_texture here";
  passes::GroundShadow shadow;
  std::string error;
  ASSERT_TRUE(shadow.init(capabilities(), {}, error)) << error;
  ASSERT_EQ(shadow.packedDepth(), packed);
  const std::vector<ibl::ShadowLight> lights = roomLights();
  ASSERT_GE(lights.size(), 6u);
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.035;
  sphere.position_w = {0.02, -0.01};
  ibl::ShadowCaster box;
  box.shape = ibl::ShadowCaster::Shape::kBox;
  box.box_size_m = {0.05, 0.03, 0.06};
  box.box_yaw_rad = 0.4;
  for (const auto& [name, caster] : {std::pair{"sphere", sphere}, std::pair{"box", box}}) {
    ASSERT_TRUE(shadow.update(lights, caster, error)) << error;
    EXPECT_EQ(shadow.shadowPassesLastUpdate(), static_cast<int>(lights.size()));
    const auto fraction = shadow.readFraction(error);
    ASSERT_TRUE(fraction) << error;
    const ShadowComparison c = compareWithReference(shadow, *fraction, caster, lights);
    std::printf("[ shadow   ] %-6s %s, %zu lights: GPU vs CPU model mean |error| %.4f, p99 %.3f, max %.3f (region %.3f m)\n", name,
                shadow.depthStorageDescription().c_str(), lights.size(), c.mean_abs, c.p99_abs, c.max_abs,
                shadow.region().half_size_m);
    // 16 PCF taps per light estimate its hidden share to 1/16 at a
    // penumbra texel, the blocker search's mean distance stands in for the
    // occluder's shape (PCSS), and the 8-bit output adds 1/510: errors live
    // in the penumbrae, a minority of the region. Measured: mean 0.0015-
    // 0.0018, p99 0.011-0.018, max 0.09-0.14 (a light's share, up to ~0.5,
    // times a quarter of its taps at a silhouette corner). Bounds: mean
    // 0.005, p99 0.03, max 0.2.
    EXPECT_LT(c.mean_abs, 0.005) << name;
    EXPECT_LT(c.p99_abs, 0.03) << name;
    EXPECT_LT(c.max_abs, 0.2) << name;
  }
}

INSTANTIATE_TEST_SUITE_P(DepthStorage, GroundShadowTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("PackedRGBA8") : std::string("DepthTexture");
                         });

// The depth pass culls the faces toward the light (it keeps the far side),
// so the caster's triangles must all be counter-clockwise seen from
// outside: the normal by the right-hand rule points away from the centre.
TEST(CasterTriangles, AreCounterClockwiseSeenFromOutside) {
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.035;
  sphere.position_w = {0.02, -0.01};
  ibl::ShadowCaster box;
  box.shape = ibl::ShadowCaster::Shape::kBox;
  box.box_size_m = {0.05, 0.03, 0.06};
  box.box_yaw_rad = 0.4;
  for (const auto& [name, caster] : {std::pair{"sphere", sphere}, std::pair{"box", box}}) {
    const std::vector<glm::vec3> triangles = passes::casterTriangles(caster);
    ASSERT_EQ(triangles.size() % 3, 0u);
    const glm::vec3 centre(caster.boundingCentre());
    int inward = 0, degenerate = 0;
    for (std::size_t k = 0; k < triangles.size(); k += 3) {
      const glm::vec3 n = glm::cross(triangles[k + 1] - triangles[k], triangles[k + 2] - triangles[k]);
      const glm::vec3 outward = (triangles[k] + triangles[k + 1] + triangles[k + 2]) / 3.0f - centre;
      const float along = glm::dot(n, outward);
      // Pole triangles of the sphere collapse to a line (two equal corners).
      if (glm::length(n) < 1e-12f) ++degenerate;
      else if (!(along > 0.0f)) ++inward;
    }
    EXPECT_EQ(inward, 0) << name;
    EXPECT_LT(degenerate, static_cast<int>(triangles.size() / 3) / 8) << name;
  }
}

// Each light is drawn only over shadowFootprintNdc. Every ground point that
// the light's cone can hide from the object (the CPU model, with the light
// alone) must lie in that quad, for high and low lights, sharp and wide
// ones, a sphere and a box; and for a high light the quad must be a small
// part of the square, or nothing is saved.
TEST(ShadowFootprint, HoldsEveryGroundPointTheLightsConeCanHide) {
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.035;
  sphere.position_w = {0.03, -0.02};
  ibl::ShadowCaster box;
  box.shape = ibl::ShadowCaster::Shape::kBox;
  box.box_size_m = {0.05, 0.03, 0.08};
  box.box_yaw_rad = 0.7;
  const int map_size = passes::GroundShadowSettings{}.shadow_map_size_px;
  auto inside = [](const std::array<glm::dvec2, 4>& q, const glm::dvec2& p) {
    double sign = 0.0;
    for (int k = 0; k < 4; ++k) {
      const glm::dvec2 e = q[(k + 1) % 4] - q[k], r = p - q[k];
      const double cross = e.x * r.y - e.y * r.x;
      if (sign == 0.0) sign = cross;
      if (cross * sign < 0.0) return false;
    }
    return true;
  };
  int hidden_points = 0;
  for (const auto& [name, caster] : {std::pair{"sphere", sphere}, std::pair{"box", box}})
    for (double elevation : {12.0, 30.0, 60.0, 88.0})
      for (double azimuth : {0.0, 75.0, 210.0})
        for (double cone_deg : {0.25, 5.0, 25.0}) {
          ibl::ShadowLight light;
          light.direction_w = direction(azimuth, elevation);
          light.share_rgb = glm::dvec3(1.0);
          light.cone_radius_rad = glm::radians(cone_deg);
          // The region as a dome sizes it: for its lowest light too.
          ibl::ShadowLight lowest = light;
          lowest.direction_w = direction(azimuth + 140.0, 12.0);
          const ibl::GroundRegion region = ibl::groundShadowRegion(caster, {light, lowest}, 0.5);
          const passes::LightView view =
              passes::lightViewFor(light.direction_w, caster.boundingCentre(), caster.boundingRadius());
          const std::array<glm::dvec2, 4> quad =
              passes::shadowFootprintNdc(view, std::tan(light.cone_radius_rad), map_size, region);
          int missed = 0;
          const int grid = 120;
          for (int j = 0; j < grid; ++j)
            for (int i = 0; i < grid; ++i) {
              const glm::dvec2 ndc((2.0 * i + 1.0) / grid - 1.0, (2.0 * j + 1.0) / grid - 1.0);
              const glm::dvec2 p = region.centre_w + region.half_size_m * ndc;
              if (ibl::groundLightFraction(p, caster, {light}, 64).g > 0.999) continue;
              ++hidden_points;
              if (!inside(quad, ndc)) ++missed;
            }
          EXPECT_EQ(missed, 0) << name << " elevation " << elevation << " azimuth " << azimuth << " cone " << cone_deg;
          if (elevation >= 60.0 && cone_deg <= 5.0) {
            // The quad's area (shoelace) against the square's 4.
            double area = 0.0;
            for (int k = 0; k < 4; ++k) area += quad[k].x * quad[(k + 1) % 4].y - quad[(k + 1) % 4].x * quad[k].y;
            std::printf("[ footprint] %s, light at %.0f deg, cone %.2f deg: %.1f%% of the square\n", name, elevation, cone_deg,
                        100.0 * 0.5 * std::abs(area) / 4.0);
            EXPECT_LT(0.5 * std::abs(area), 0.25 * 4.0) << name << " elevation " << elevation << " cone " << cone_deg;
          }
        }
  EXPECT_GT(hidden_points, 10000);
}

// A uniform floor of sRGB code 180 seen by the test camera, and the passes
// that draw the shadow over it: init(), then shadow.update(...), then
// composite(pose) gives the frame.
struct GreyFloorComposite {
  const CameraIntrinsics camera = test::testCamera();
  passes::CameraFrameTexture texture;
  passes::ObjectCompositor compositor;
  passes::GroundShadow shadow;
  gles::RenderTarget target;
  bool init(std::string& error) {
    ImageRGB8 frame;
    frame.resize(camera.width_px, camera.height_px);
    std::fill(frame.pixels.begin(), frame.pixels.end(), std::uint8_t{180});
    return texture.init(test::sharedCapabilities(), error) && texture.upload(frame, error) &&
           compositor.init(test::sharedCapabilities(), {}, passes::CubeStorage::kSrgb8, error) &&
           shadow.init(test::sharedCapabilities(), {}, error) &&
           target.init(camera.width_px, camera.height_px, error);
  }
  bool composite(const PoseCamFromWorld& pose, ImageRGB8& out, std::string& error) {
    target.bind();
    compositor.drawCameraBackground(texture);
    return shadow.drawOnCameraImage(camera, pose, texture, error) && target.readRGB(out, error);
  }
};

// The composite: a uniform floor of sRGB code 180 under an overhead light
// that carries half the ground's light, with a sphere: under it the floor
// must read encode(0.5 decode(180)), away from it 180, and pixels the ground
// square does not cover are untouched.
TEST_F(GpuTest, CompositeDarkensTheCameraPixelsByTheFractionInLinearLight) {
  std::string error;
  GreyFloorComposite floor;
  ASSERT_TRUE(floor.init(error)) << error;
  const CameraIntrinsics& camera = floor.camera;
  passes::GroundShadow& shadow = floor.shadow;
  const PoseCamFromWorld pose = test::lookAt({0.0, -0.35, 0.45}, {0.0, 0.0, 0.0});
  ibl::ShadowLight overhead;
  overhead.direction_w = {0, 0, 1};
  overhead.share_rgb = glm::dvec3(0.5);
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.04;
  ASSERT_TRUE(shadow.update({overhead}, sphere, error)) << error;
  ImageRGB8 out;
  ASSERT_TRUE(floor.composite(pose, out, error)) << error;
  const double expected_code = 255.0 * ibl::linearToSrgb(0.5 * ibl::srgbToLinear(180.0 / 255.0));
  // Where the centre of the disc under the sphere, and a point of the
  // square well outside the disc (0.8 r from a corner), land in the image.
  auto pixelOf = [&](const glm::dvec3& p_w) {
    const glm::dvec2 px = ibl::projectToPixel(camera, pose.toCamera(p_w));
    return glm::ivec2(static_cast<int>(std::lround(px.x)), static_cast<int>(std::lround(px.y)));
  };
  const glm::ivec2 under = pixelOf({0.0, 0.0, 0.0});
  const double half = shadow.region().half_size_m;
  const glm::ivec2 lit = pixelOf({0.9 * half, 0.9 * half, 0.0});
  const glm::ivec2 outside = pixelOf({3.0 * half, 0.0, 0.0});
  auto code = [&](const glm::ivec2& p) { return static_cast<double>(out.pixels[(static_cast<std::size_t>(p.y) * out.width + p.x) * 3 + 1]); };
  std::printf("[ composite] floor 180: under the sphere %.0f (expected %.1f), lit ground %.0f, outside %.0f\n", code(under),
              expected_code, code(lit), code(outside));
  // One code for the 8-bit fraction and one for the re-encoding.
  EXPECT_NEAR(code(under), expected_code, 2.0);
  EXPECT_NEAR(code(lit), 180.0, 1.0);
  EXPECT_EQ(code(outside), 180.0);
}

// The composite draws only the grid cells the shadow darkens: everywhere
// the ground square covers, the frame must still be the full composite,
// encode(decode(180) f), where f is the fraction at that point. A pixel's
// centre falls between ground texels, so its f lies between the least and
// the greatest of the texel's 3 x 3 neighbourhood (bilinear weights are
// convex); one code more each way for the re-encoding's rounding. The
// room's dome casts several long streaks, so whole cells are skipped.
TEST_F(GpuTest, CompositeOfTheDarkenedCellsIsTheFullCompositeEverywhere) {
  std::string error;
  GreyFloorComposite floor;
  ASSERT_TRUE(floor.init(error)) << error;
  const CameraIntrinsics& camera = floor.camera;
  passes::GroundShadow& shadow = floor.shadow;
  const passes::GroundShadowSettings settings;  // what init() gave it
  const PoseCamFromWorld pose = test::lookAt({0.05, -0.4, 0.5}, {0.0, 0.0, 0.0});
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.035;
  ASSERT_TRUE(shadow.update(roomLights(), sphere, error)) << error;
  ASSERT_TRUE(shadow.hasShadow());
  const auto fraction = shadow.readFraction(error);
  ASSERT_TRUE(fraction) << error;
  const int n = shadow.groundTextureSizePx();
  const std::vector<bool> cells = passes::darkeningCells(*fraction, n, settings.region_mesh_segments);
  const auto drawn = std::count(cells.begin(), cells.end(), true);
  EXPECT_GT(drawn, 0);
  EXPECT_LT(drawn, static_cast<long>(cells.size()) * 3 / 4) << "the streaks leave most cells out";

  ImageRGB8 out;
  ASSERT_TRUE(floor.composite(pose, out, error)) << error;
  const double linear_180 = ibl::srgbToLinear(180.0 / 255.0);
  int checked = 0, darkened = 0, outside_bounds = 0;
  for (int j = 1; j + 1 < n; ++j)
    for (int i = 1; i + 1 < n; ++i) {
      float least = 1.0f, greatest = 0.0f;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const float f = (*fraction)[static_cast<std::size_t>(j + dj) * n + (i + di)].g;
          least = std::min(least, f);
          greatest = std::max(greatest, f);
        }
      const glm::dvec2 p = shadow.groundPointOfTexel(i, j);
      const glm::dvec2 px = ibl::projectToPixel(camera, pose.toCamera({p, 0.0}));
      const int x = static_cast<int>(std::floor(px.x)), y = static_cast<int>(std::floor(px.y));
      if (x < 0 || y < 0 || x >= camera.width_px || y >= camera.height_px) continue;
      const double code = out.pixels[(static_cast<std::size_t>(y) * out.width + x) * 3 + 1];
      const double low = 255.0 * ibl::linearToSrgb(linear_180 * least) - 1.0;
      const double high = 255.0 * ibl::linearToSrgb(linear_180 * greatest) + 1.0;
      ++checked;
      if (code < 179.5) ++darkened;
      if (code < low || code > high) ++outside_bounds;
    }
  std::printf("[ composite] %ld of %zu cells drawn; %d ground texels on screen, %d darkened, %d off the full composite\n",
              static_cast<long>(drawn), cells.size(), checked, darkened, outside_bounds);
  EXPECT_GT(checked, 10000);
  EXPECT_GT(darkened, 1000);
  EXPECT_EQ(outside_bounds, 0);
}

TEST(DarkeningCells, ATexelOneStepDarkMarksItsCellAndTheCellsItsNeighboursFallIn) {
  const int n = 16, segments = 4;  // 4 x 4 texels a cell
  std::vector<glm::vec3> fraction(static_cast<std::size_t>(n) * n, glm::vec3(1.0f));
  auto count = [](const std::vector<bool>& cells) { return std::count(cells.begin(), cells.end(), true); };
  EXPECT_EQ(count(passes::darkeningCells(fraction, n, segments)), 0);
  // Not a step darker: 254.6 / 255 in every channel draws nothing.
  fraction[5 * n + 5] = glm::vec3(254.6f / 255.0f);
  EXPECT_EQ(count(passes::darkeningCells(fraction, n, segments)), 0);
  // One channel a step darker, inside cell (1, 1): that cell alone.
  fraction[5 * n + 5] = glm::vec3(1.0f, 254.4f / 255.0f, 1.0f);
  std::vector<bool> cells = passes::darkeningCells(fraction, n, segments);
  EXPECT_EQ(count(cells), 1);
  EXPECT_TRUE(cells[1 * segments + 1]);
  // A texel on cell (2, 1)'s left edge: its left neighbour lies in cell (1, 1).
  fraction[5 * n + 5] = glm::vec3(1.0f);
  fraction[6 * n + 8] = glm::vec3(0.5f);
  cells = passes::darkeningCells(fraction, n, segments);
  EXPECT_EQ(count(cells), 2);
  EXPECT_TRUE(cells[1 * segments + 1]);
  EXPECT_TRUE(cells[1 * segments + 2]);
  // A corner texel of cell (1, 1) at (7, 7): four cells share its neighbourhood.
  fraction[6 * n + 8] = glm::vec3(1.0f);
  fraction[7 * n + 7] = glm::vec3(0.0f);
  EXPECT_EQ(count(passes::darkeningCells(fraction, n, segments)), 4);
  // A size that does not divide: 10 texels over 4 cells still covers every texel.
  std::vector<glm::vec3> odd(100, glm::vec3(1.0f));
  odd[9 * 10 + 9] = glm::vec3(0.0f);
  cells = passes::darkeningCells(odd, 10, segments);
  EXPECT_TRUE(cells[3 * segments + 3]);
  EXPECT_EQ(count(cells), 1);
}

// Stress: all finite and sensible. A light a hair above the horizon (the
// ground's depth slope in its map goes as 1 / z), a big object whose shadow
// the region's cap cuts off, a tiny one, one far from the tag.
TEST_F(GpuTest, ShadowStaysFiniteForGrazingLightsAndOddObjects) {
  std::string error;
  passes::GroundShadow shadow;
  ASSERT_TRUE(shadow.init(test::sharedCapabilities(), {}, error)) << error;
  ibl::ShadowLight grazing;
  grazing.direction_w = glm::normalize(glm::dvec3(1.0, 0.2, 1e-5));
  grazing.share_rgb = glm::dvec3(0.5);
  grazing.cone_radius_rad = 0.05;
  ibl::ShadowLight overhead;
  overhead.direction_w = {0, 0, 1};
  overhead.share_rgb = glm::dvec3(0.5);
  ibl::ShadowCaster big, tiny, far_away;
  big.radius_m = 0.4;
  tiny.radius_m = 1e-4;
  far_away.position_w = {25.0, -40.0};
  // (A tiny object under a grazing light would get a square the cap makes
  // 0.5 m wide: its 0.2 mm shadow falls between 4 mm texels. In practice a
  // grazing light's share of the ground's light, rgb z / E, is nil and
  // groundShadowLights drops it; so the tiny object gets the overhead light.)
  for (const auto& [name, caster, lights] :
       {std::tuple{"big", big, std::vector<ibl::ShadowLight>{grazing, overhead}},
        std::tuple{"tiny", tiny, std::vector<ibl::ShadowLight>{overhead}},
        std::tuple{"far away", far_away, std::vector<ibl::ShadowLight>{grazing, overhead}}}) {
    ASSERT_TRUE(shadow.update(lights, caster, error)) << name << ": " << error;
    EXPECT_LE(shadow.region().half_size_m, 0.5) << name << ": the cap holds";
    const auto fraction = shadow.readFraction(error);
    ASSERT_TRUE(fraction) << error;
    float darkest = 1.0f;
    for (const glm::vec3& f : *fraction) {
      ASSERT_TRUE(std::isfinite(f.g)) << name;
      darkest = std::min(darkest, f.g);
    }
    // The overhead light's disc is under every object (0.5 of the light);
    // the grazing light's shadow may add to it: 0 to 0.5.
    EXPECT_LE(darkest, 0.5f + 1.0f / 255.0f) << name;
    EXPECT_GE(darkest, 0.0f) << name;
  }
}

TEST_F(GpuTest, NoLightsMeansNoShadowAndNothingDrawn) {
  std::string error;
  passes::GroundShadow shadow;
  ASSERT_TRUE(shadow.init(test::sharedCapabilities(), {}, error)) << error;
  ASSERT_TRUE(shadow.update({}, ibl::ShadowCaster{}, error)) << error;
  EXPECT_FALSE(shadow.hasShadow());
  EXPECT_EQ(shadow.shadowPassesLastUpdate(), 0);
}

}  // namespace
}  // namespace probelight
