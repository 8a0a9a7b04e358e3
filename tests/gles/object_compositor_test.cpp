// Stage 4 on the GPU: background, object placement (distorted projection)
// and shading, against ibl::projectToPixel, ibl::pixelToCameraRay and
// ibl::shadeSurface.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <optional>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/constants.hpp>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/surface_shading.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/object_compositor.hpp"

namespace probelight {
namespace {

using test::GpuTest;

// An image with no symmetry: a flip or transpose changes many pixels.
ImageRGB8 asymmetricImage(int width, int height) {
  ImageRGB8 image;
  image.resize(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.row(y)[3 * x + 0] = static_cast<std::uint8_t>((x * 7 + y * 3) & 255);
      image.row(y)[3 * x + 1] = static_cast<std::uint8_t>((y * 5) & 255);
      image.row(y)[3 * x + 2] = static_cast<std::uint8_t>((x * y) >> 4 & 255);
    }
  }
  return image;
}

struct Stage4 {
  gles::RenderTarget target;
  passes::CameraFrameTexture frame;
  passes::EnvironmentMaps maps;
  passes::ObjectCompositor compositor;
};

void initStage4(Stage4& stage, const gles::Capabilities& caps, int width, int height) {
  std::string error;
  ASSERT_TRUE(stage.target.init(width, height, error)) << error;
  ASSERT_TRUE(stage.frame.init(caps, error)) << error;
  ASSERT_TRUE(stage.maps.init(caps, {}, error)) << error;
  ASSERT_TRUE(stage.compositor.init(caps, {}, stage.maps.storage(), error)) << error;
}

// The background is the camera frame, byte for byte, upright: the quad
// samples every texel at its exact centre, where GL_LINEAR returns that texel
// (the neighbours' weights are 0 to within fp32 interpolation, far below the
// 1/256 weight step), so any difference is a flip, shift or colour change.
TEST_F(GpuTest, BackgroundIsDrawnUprightAndUnmodified) {
  const ImageRGB8 image = asymmetricImage(320, 240);
  Stage4 stage;
  initStage4(stage, test::sharedCapabilities(), image.width, image.height);
  std::string error;
  ASSERT_TRUE(stage.frame.upload(image, error)) << error;
  stage.target.bind();
  stage.compositor.drawCameraBackground(stage.frame);
  ImageRGB8 result;
  ASSERT_TRUE(stage.target.readRGB(result, error)) << error;
  ASSERT_EQ(result.pixels.size(), image.pixels.size());
  int differing = 0;
  for (size_t i = 0; i < image.pixels.size(); ++i) differing += image.pixels[i] != result.pixels[i];
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(result.row(0)[1], image.row(0)[1]);
  EXPECT_EQ(result.row(239)[1], image.row(239)[1]);
}

// Straight alpha over the background: alpha 255 replaces, alpha 0 keeps.
// 8-bit blending rounds once: +-1 level.
TEST_F(GpuTest, OverlayBlendsByAlphaInImageOrientation) {
  const ImageRGB8 image = asymmetricImage(64, 48);
  Stage4 stage;
  initStage4(stage, test::sharedCapabilities(), image.width, image.height);
  std::string error;
  ASSERT_TRUE(stage.frame.upload(image, error)) << error;
  std::vector<std::uint8_t> overlay(64 * 48 * 4, 0);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 16; ++x) {
      std::uint8_t* p = &overlay[static_cast<size_t>((y * 64 + x) * 4)];
      p[0] = 255;
      p[3] = 255;
    }
  }
  stage.target.bind();
  stage.compositor.drawCameraBackground(stage.frame);
  ASSERT_TRUE(stage.compositor.drawOverlayRGBA(overlay.data(), 64, 48, error)) << error;
  ImageRGB8 result;
  ASSERT_TRUE(stage.target.readRGB(result, error)) << error;
  EXPECT_EQ(result.row(2)[3 * 5 + 0], 255);  // top-left block is red
  EXPECT_EQ(result.row(2)[3 * 5 + 1], 0);
  EXPECT_NEAR(result.row(40)[3 * 5 + 1], image.row(40)[3 * 5 + 1], 1);  // below it: background
  EXPECT_NEAR(result.row(2)[3 * 40 + 0], image.row(2)[3 * 40 + 0], 1);
}

struct SphereScene {
  CameraIntrinsics camera = test::testCamera();
  // Placed off-centre, where distortion moves it by several pixels.
  PoseCamFromWorld pose = test::lookAt({0.05, -0.40, 0.28}, {-0.12, 0.02, 0.0});
  glm::dvec3 centre_w{0.06, 0.05, 0.05};
  double radius_m = 0.05;
};

// Outline of the sphere as the camera sees it: the circle where the tangent
// cone from the camera centre touches it, projected with distortion.
std::vector<glm::dvec2> projectedOutline(const SphereScene& scene, bool with_distortion) {
  CameraIntrinsics camera = scene.camera;
  if (!with_distortion) camera.distortion = {0, 0, 0, 0, 0};
  const glm::dvec3 eye = scene.pose.cameraCenterWorld();
  const glm::dvec3 to_centre = scene.centre_w - eye;
  const double distance = glm::length(to_centre);
  const glm::dvec3 axis = to_centre / distance;
  const glm::dvec3 u = glm::normalize(glm::cross(axis, glm::dvec3(0.0, 0.0, 1.0)));
  const glm::dvec3 v = glm::cross(axis, u);
  const double r = scene.radius_m;
  const glm::dvec3 ring_centre = scene.centre_w - (r * r / distance) * axis;
  const double ring_radius = r * std::sqrt(1.0 - r * r / (distance * distance));
  std::vector<glm::dvec2> outline;
  for (int i = 0; i < 1440; ++i) {
    const double phi = 2.0 * glm::pi<double>() * i / 1440.0;
    const glm::dvec3 point = ring_centre + ring_radius * (std::cos(phi) * u + std::sin(phi) * v);
    outline.push_back(ibl::projectToPixel(camera, scene.pose.toCamera(point)));
  }
  return outline;
}

double distanceToPolygon(const std::vector<glm::dvec2>& polygon, const glm::dvec2& p, bool& inside) {
  double best = 1e30;
  inside = false;
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const glm::dvec2 a = polygon[j];
    const glm::dvec2 b = polygon[i];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
    const glm::dvec2 ab = b - a;
    const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
    best = std::min(best, glm::length(p - (a + t * ab)));
  }
  return best;
}

// Pixels whose centre lies more than 0.75 px inside (outside) the calibrated
// outline must be covered (uncovered). Budget: the 64x32 facets lie inside
// the sphere by at most radius * (1 - cos^2(pi/64)) = 0.0024 radius, ~0.2 px
// for this ~80 px-radius outline; fp32 projection ~1e-4 px; rasterisation
// samples pixel centres exactly, so 0.75 px leaves margin while a projection
// without distortion (checked to be > 3 px off here) fails.
TEST_F(GpuTest, SphereSilhouetteLandsOnTheDistortedProjection) {
  const SphereScene scene;
  Stage4 stage;
  initStage4(stage, test::sharedCapabilities(), scene.camera.width_px, scene.camera.height_px);
  std::string error;
  ImageRGB8 black;
  black.resize(scene.camera.width_px, scene.camera.height_px);
  ASSERT_TRUE(stage.frame.upload(black, error)) << error;
  ibl::SurfaceMaterial white;
  white.ambient = 1.0f;
  white.k_diffuse = 0.0f;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = glm::vec3(1.0f);
  stage.target.bind();
  stage.compositor.drawCameraBackground(stage.frame);
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(stage.compositor.drawSphereObject(scene.camera, scene.pose, scene.centre_w, scene.radius_m, white,
                                                lighting, stage.maps, error))
      << error;
  glFinish();
  const double draw_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ImageRGB8 result;
  ASSERT_TRUE(stage.target.readRGB(result, error)) << error;

  const std::vector<glm::dvec2> outline = projectedOutline(scene, true);
  const std::vector<glm::dvec2> undistorted = projectedOutline(scene, false);
  double distortion_shift_px = 0.0;
  for (size_t i = 0; i < outline.size(); ++i) {
    distortion_shift_px = std::max(distortion_shift_px, glm::length(outline[i] - undistorted[i]));
  }
  ASSERT_GT(distortion_shift_px, 3.0) << "the scene must make distortion matter for this test to have teeth";

  int wrong = 0;
  int covered = 0;
  double area_px = 0.0;
  for (size_t i = 0, j = outline.size() - 1; i < outline.size(); j = i++) {
    area_px += 0.5 * (outline[j].x * outline[i].y - outline[i].x * outline[j].y);
  }
  glm::dvec2 low(1e30);
  glm::dvec2 high(-1e30);
  for (const glm::dvec2& p : outline) {
    low = glm::min(low, p);
    high = glm::max(high, p);
  }
  for (int y = 0; y < result.height; ++y) {
    for (int x = 0; x < result.width; ++x) {
      const bool gpu_covered = result.row(y)[3 * x] > 127;
      covered += gpu_covered;
      const bool near_outline = x > low.x - 2 && x < high.x + 2 && y > low.y - 2 && y < high.y + 2;
      if (!near_outline) {
        wrong += gpu_covered;
        continue;
      }
      bool inside = false;
      const double distance = distanceToPolygon(outline, {x, y}, inside);
      if (distance > 0.75 && gpu_covered != inside) ++wrong;
    }
  }
  std::printf("[ measure  ] sphere silhouette: %d px covered vs outline area %.1f px, max distortion shift %.1f px, "
              "draw %.2f ms\n",
              covered, std::abs(area_px), distortion_shift_px, draw_ms);
  EXPECT_EQ(wrong, 0);
  // Pixel count vs the outline's area: rasterisation at pixel centres is
  // unbiased, so they differ by the facets' inset (<= 0.2 px times the
  // perimeter) plus sampling noise; 0.3 px times the perimeter bounds both.
  const double perimeter_px = 2.0 * std::sqrt(glm::pi<double>() * std::abs(area_px)) * 1.05;
  EXPECT_NEAR(covered, std::abs(area_px), 0.3 * perimeter_px);
}

// The tessellation follows the sphere's size on screen: the fewest facets
// whose chords stay within the sag, and a radius bound that is never below
// the true silhouette's (f R / sqrt(d^2 - R^2) on the axis).
// The ladder mirror, glossy 0..L-1, diffuse as the maps the shader reads:
// kinds 0 mirror, 1 and 2 the glossy levels, 3 diffuse.
TEST(ReflectionRungs, ReadOnlyTheMapsTheBlendWeighs) {
  // Glossiness 1 is the mirror alone and 0 the diffuse map alone, whatever L.
  for (int levels : {0, 1, 2}) {
    const passes::ReflectionRungs sharp = passes::reflectionRungsFor(1.0f, levels);
    EXPECT_EQ(sharp.lower_kind, 0) << levels;
    EXPECT_EQ(sharp.upper_kind, -1) << levels;
    const passes::ReflectionRungs matte = passes::reflectionRungsFor(0.0f, levels);
    EXPECT_EQ(matte.lower_kind, 3) << levels;
    EXPECT_EQ(matte.upper_kind, -1) << levels;
  }
  // Without glossy maps, 0.25: p = 0.75 * 1 between the mirror and the diffuse map.
  const passes::ReflectionRungs no_glossy = passes::reflectionRungsFor(0.25f, 0);
  EXPECT_EQ(no_glossy.lower_kind, 0);
  EXPECT_EQ(no_glossy.upper_kind, 3);
  EXPECT_FLOAT_EQ(no_glossy.toward_upper, 0.75f);
  // Two levels, 0.45: p = 0.55 * 3 = 1.65, glossy 0 then glossy 1.
  const passes::ReflectionRungs two = passes::reflectionRungsFor(0.45f, 2);
  EXPECT_EQ(two.lower_kind, 1);
  EXPECT_EQ(two.upper_kind, 2);
  EXPECT_NEAR(two.toward_upper, 0.65f, 1e-5f);
  // One level, 0.2: p = 0.8 * 2 = 1.6, glossy 0 then the diffuse map (rung L + 1).
  const passes::ReflectionRungs one = passes::reflectionRungsFor(0.2f, 1);
  EXPECT_EQ(one.lower_kind, 1);
  EXPECT_EQ(one.upper_kind, 3);
  EXPECT_NEAR(one.toward_upper, 0.6f, 1e-5f);
}

TEST(SphereTessellation, FewestSegmentsWithinTheSagForABoundOnTheRadius) {
  const double sag_px = passes::ObjectCompositorSettings{}.max_silhouette_sag_px;
  const auto sag = [](double radius_px, int segments) { return radius_px * (1.0 - std::cos(glm::pi<double>() / segments)); };
  int previous = 0;
  for (double radius_px : {2.0, 10.0, 40.0, 56.0, 100.0, 250.0, 600.0}) {
    const int segments = passes::sphereSegmentsFor(radius_px, sag_px);
    EXPECT_LE(sag(radius_px, segments), sag_px) << radius_px;
    EXPECT_GE(segments, previous) << radius_px;  // never fewer for a larger sphere
    previous = segments;
    const auto step = std::find(std::begin(passes::kSphereSegmentSteps), std::end(passes::kSphereSegmentSteps), segments);
    ASSERT_NE(step, std::end(passes::kSphereSegmentSteps));
    if (step != std::begin(passes::kSphereSegmentSteps)) {
      EXPECT_GT(sag(radius_px, *(step - 1)), sag_px) << radius_px;
    }
  }
  // Too large for any step (or not finite): the finest.
  EXPECT_EQ(passes::sphereSegmentsFor(1e6, sag_px), 128);
  EXPECT_EQ(passes::sphereSegmentsFor(std::numeric_limits<double>::infinity(), sag_px), 128);
  for (double depth_m : {0.11, 0.3, 1.0, 5.0}) {
    const double exact = 600.0 * 0.1 / std::sqrt(depth_m * depth_m - 0.01);
    EXPECT_GE(passes::sphereSilhouetteRadiusBoundPx(600.0, 0.1, depth_m), exact) << depth_m;
  }
  EXPECT_TRUE(std::isinf(passes::sphereSilhouetteRadiusBoundPx(600.0, 0.1, 0.05)));  // camera inside the sphere
}

class SphereShadingTest : public GpuTest, public ::testing::WithParamInterface<bool> {};

// Each covered pixel away from the silhouette against ibl::shadeSurface at
// the normal found by intersecting that pixel's calibrated ray with the
// sphere, using the very maps the GPU read (read back), compared in 8-bit
// output levels. Budget per pixel:
//  - output rounding: 0.5 level; map storage is shared (read back), so none;
//  - facet normals: the flat facet lies below the sphere by the sagitta
//    (pi / rows)^2 / 8 radius (rows: the latitude segments the compositor
//    picks for this sphere's size, sphereSegmentsFor), which tilts the
//    shading normal by up to sagitta * tan(view angle) / radius, view angle
//    <= 60 deg away from the silhouette band; the tolerance adds the change
//    of the CPU shading when its normal is tilted by that (worst of four
//    tilts, at least 2.5e-3 rad), so sharp highlights and map
//    edges get the slack they need and flat regions do not;
//  - fp32 shading and llvmpipe's approximate pow: < 0.5 level.
TEST_P(SphereShadingTest, MatchesCpuShadeSurface) {
  const bool force_8bit = GetParam();
  const gles::Capabilities caps =
      force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
  const SphereScene scene;
  Stage4 stage;
  initStage4(stage, caps, scene.camera.width_px, scene.camera.height_px);
  std::string error;
  ibl::CubeMapRGB environment(stage.maps.settings().reflection_face_size);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < environment.face_size; ++y) {
      for (int x = 0; x < environment.face_size; ++x) {
        environment.texel(face, x, y) = glm::vec3(
            test::analyticEnvironment(ibl::cubeTexelCenterDirection(face, x, y, environment.face_size)));
      }
    }
  }
  ASSERT_TRUE(stage.maps.setReflection(environment, error)) << error;
  ASSERT_TRUE(stage.maps.updateDiffuse(error)) << error;
  const auto diffuse = stage.maps.readDiffuse(error);
  ASSERT_TRUE(diffuse) << error;
  const auto reflection = stage.maps.readReflection(error);
  ASSERT_TRUE(reflection) << error;
  // Glossy levels too, so the loop below checks glossiness 1 (today's
  // mirror), 0 (the diffuse lobe) and one value between glossy maps.
  ASSERT_TRUE(stage.maps.updateGlossy(error)) << error;
  std::vector<ibl::CubeMapRGB> glossy_maps;
  for (int level = 0; level < stage.maps.glossyLevels(); ++level) {
    const auto glossy = stage.maps.readGlossy(level, error);
    ASSERT_TRUE(glossy) << error;
    glossy_maps.push_back(*glossy);
  }
  std::vector<const ibl::CubeMapRGB*> glossy;
  for (const auto& map : glossy_maps) glossy.push_back(&map);
  for (const float glossiness : {1.0f, 0.45f, 0.0f}) {

  ImageRGB8 grey;
  grey.resize(scene.camera.width_px, scene.camera.height_px);
  std::fill(grey.pixels.begin(), grey.pixels.end(), 90);
  ASSERT_TRUE(stage.frame.upload(grey, error)) << error;
  ibl::SurfaceMaterial material;
  material.albedo = {0.9f, 0.7f, 0.5f};
  material.ambient = 0.2f;
  material.k_diffuse = 0.8f;
  material.k_specular = 0.3f;
  material.shininess = 24.0f;
  material.k_reflect = 0.25f;
  material.glossiness = glossiness;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = {0.1f, 0.1f, 0.12f};
  lighting.highlight_direction_w = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
  lighting.highlight_rgb = {0.8f, 0.75f, 0.7f};
  stage.target.bind();
  stage.compositor.drawCameraBackground(stage.frame);
  ASSERT_TRUE(stage.compositor.drawSphereObject(scene.camera, scene.pose, scene.centre_w, scene.radius_m, material,
                                                lighting, stage.maps, error))
      << error;
  ImageRGB8 result;
  ASSERT_TRUE(stage.target.readRGB(result, error)) << error;

  const glm::dvec3 eye = scene.pose.cameraCenterWorld();
  const glm::dmat3 world_from_cam = glm::transpose(scene.pose.R_cam_from_world);
  const int latitude_rows =
      passes::sphereSegmentsFor(passes::sphereSilhouetteRadiusBoundPx(std::max(scene.camera.fx_px, scene.camera.fy_px),
                                                                      scene.radius_m,
                                                                      scene.pose.toCamera(scene.centre_w).z),
                                passes::ObjectCompositorSettings{}.max_silhouette_sag_px) /
      2;
  const float tilt_rad = std::max(
      2.5e-3f, static_cast<float>(std::pow(glm::pi<double>() / latitude_rows, 2.0) / 8.0 * std::tan(glm::radians(60.0))));
  auto shade_levels = [&](const glm::vec3& normal, const glm::vec3& to_eye) {
    const glm::vec3 linear = ibl::shadeSurface(normal, to_eye, *diffuse, *reflection, glossy, material, lighting);
    return glm::dvec3(ibl::linearToSrgb(linear.r), ibl::linearToSrgb(linear.g), ibl::linearToSrgb(linear.b)) * 255.0;
  };
  int compared = 0;
  double max_error = 0.0;
  double max_excess = -1e9;
  for (int y = 0; y < result.height; ++y) {
    for (int x = 0; x < result.width; ++x) {
      const glm::dvec3 ray = glm::normalize(world_from_cam * ibl::pixelToCameraRay(scene.camera, {x, y}));
      const glm::dvec3 to_centre = scene.centre_w - eye;
      const double along = glm::dot(ray, to_centre);
      const double miss2 = glm::dot(to_centre, to_centre) - along * along;
      const double r2 = scene.radius_m * scene.radius_m;
      if (miss2 >= r2) continue;
      const glm::dvec3 hit = eye + (along - std::sqrt(r2 - miss2)) * ray;
      const glm::dvec3 normal = glm::normalize(hit - scene.centre_w);
      if (glm::dot(normal, -ray) < 0.5) continue;  // > 60 deg from the eye: near the silhouette
      const glm::vec3 n(normal);
      const glm::vec3 to_eye(-ray);
      const glm::dvec3 expected = shade_levels(n, to_eye);
      const glm::vec3 tangent_a = glm::normalize(glm::cross(n, glm::vec3(0.0f, 0.0f, 1.0f)));
      const glm::vec3 tangent_b = glm::cross(n, tangent_a);
      glm::dvec3 sensitivity(0.0);
      for (const glm::vec3& tilt : {tangent_a, -tangent_a, tangent_b, -tangent_b}) {
        sensitivity = glm::max(sensitivity, glm::abs(shade_levels(glm::normalize(n + tilt_rad * tilt), to_eye) - expected));
      }
      for (int c = 0; c < 3; ++c) {
        const double gpu = result.row(y)[3 * x + c];
        const double expected_levels = std::clamp(expected[c], 0.0, 255.0);
        const double error_levels = std::abs(gpu - expected_levels);
        max_error = std::max(max_error, error_levels);
        max_excess = std::max(max_excess, error_levels - (1.0 + sensitivity[c]));
      }
      ++compared;
    }
  }
  std::printf("[ measure  ] sphere shading (%s maps, glossiness %.2f): %d px compared, max |GPU-CPU| %.2f levels\n",
              stage.maps.storageDescription().c_str(), glossiness, compared, max_error);
  EXPECT_GT(compared, 5000);
  EXPECT_LE(max_excess, 0.0);
  }
}

// Not a pass/fail benchmark: prints per-stage times on this GPU (after one
// warm-up frame, which includes llvmpipe's shader JIT) and checks that a
// frame's stages leave no GL error behind.
TEST_F(GpuTest, ReportsStageTimes) {
  const SphereScene scene;
  for (const bool force_8bit : {false, true}) {
    const gles::Capabilities caps =
        force_8bit ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
    Stage4 stage;
    initStage4(stage, caps, scene.camera.width_px, scene.camera.height_px);
    std::string error;
    const ImageRGB8 image = asymmetricImage(scene.camera.width_px, scene.camera.height_px);
    ibl::MirrorBallView view{scene.camera, scene.pose, {0.12, 0.0, 0.08}, 0.03};
    double upload_ms = 0, probe_ms = 0, blur_ms = 0, draw_ms = 0;
    constexpr int kFrames = 5;
    for (int frame = 0; frame <= kFrames; ++frame) {
      auto lap = [](std::chrono::steady_clock::time_point& since) {
        glFinish();
        const auto now = std::chrono::steady_clock::now();
        const double ms = std::chrono::duration<double, std::milli>(now - since).count();
        since = now;
        return ms;
      };
      auto since = std::chrono::steady_clock::now();
      ASSERT_TRUE(stage.frame.upload(image, error)) << error;
      const double upload = lap(since);
      ASSERT_TRUE(stage.maps.updateReflection(stage.frame, view, 0.7, error)) << error;
      const double probe = lap(since);
      ASSERT_TRUE(stage.maps.updateDiffuse(error)) << error;
      const double blur = lap(since);
      stage.target.bind();
      stage.compositor.drawCameraBackground(stage.frame);
      ASSERT_TRUE(stage.compositor.drawSphereObject(scene.camera, scene.pose, scene.centre_w, scene.radius_m, {}, {},
                                                    stage.maps, error))
          << error;
      const double draw = lap(since);
      if (frame == 0) continue;
      upload_ms += upload / kFrames;
      probe_ms += probe / kFrames;
      blur_ms += blur / kFrames;
      draw_ms += draw / kFrames;
    }
    EXPECT_TRUE(gles::checkGl("frame", error)) << error;
    std::printf("[ measure  ] %s: upload 640x480 %.2f ms, probe->cube 6x64^2 %.2f ms, blur 2 passes 6x32^2 %.2f ms, "
                "background + sphere %.2f ms\n",
                stage.maps.storageDescription().c_str(), upload_ms, probe_ms, blur_ms, draw_ms);
  }
}

INSTANTIATE_TEST_SUITE_P(Storage, SphereShadingTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? std::string("Forced8Bit") : std::string("Native");
                         });

}  // namespace
}  // namespace probelight
