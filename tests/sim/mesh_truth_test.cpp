// The simulator's truth for a user's model: its ground shadow against the
// analytic box's, and its path-traced radiance against brute-force
// integrals of the same BRDF over the sky (which the path tracer reaches by
// importance sampling, shadow rays and multiple importance sampling).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "core/math_constants.hpp"
#include "model/generated_models.hpp"
#include "sim/environment.hpp"
#include "sim/gltf_brdf.hpp"
#include "sim/occluder.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

double luminance(const glm::dvec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; }

// A box model standing at (x, y) on the ground, as meshOccluder places it.
VirtualOccluder boxMesh(const glm::dvec3& size_m, const glm::dvec2& at_w, double yaw_deg, const model::Material& material) {
  auto box = std::make_shared<const model::MeshModel>(model::boxModel(size_m, material));
  glm::dmat4 world_from_model(1.0);
  const double yaw = yaw_deg * kPi / 180.0;
  world_from_model[0] = glm::dvec4(std::cos(yaw), std::sin(yaw), 0.0, 0.0);
  world_from_model[1] = glm::dvec4(-std::sin(yaw), std::cos(yaw), 0.0, 0.0);
  world_from_model[3] = glm::dvec4(at_w, 0.5 * size_m.z, 1.0);
  return meshOccluder(box, world_from_model);
}

// The mesh's shadow is decided ray by ray, the analytic box's by its exact
// outline: the same box both ways must cast the same shadow, to the
// mesh's stated error (its dim cells decided by their centre: < 9e-5 of
// E_up each, of either sign along the outline; its bright pieces at 0.027
// deg).
TEST(MeshTruth, AMeshBoxCastsTheAnalyticBoxsShadow) {
  for (const char* environment : {"sun_sky", "studio"}) {
    SceneConfig scene = defaultScene();
    scene.environment = environment;
    const World world(scene);
    VirtualOccluder analytic;
    analytic.shape = VirtualOccluder::Shape::kBox;
    analytic.position_w = {-0.10, -0.05};
    analytic.box_size_m = {0.05, 0.04, 0.07};
    analytic.box_yaw_deg = 25.0;
    const VirtualOccluder mesh = boxMesh(analytic.box_size_m, analytic.position_w, analytic.box_yaw_deg, {});
    std::vector<glm::dvec2> points;
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 24; ++i) {
        const glm::dvec2 p = analytic.position_w + 0.16 * glm::dvec2((2.0 * i + 1.0) / 24.0 - 1.0, (2.0 * j + 1.0) / 24.0 - 1.0);
        if (intersectOccluder(analytic, glm::dvec3(p, 1e-6), {0.0, 0.0, 1.0})) continue;  // under it
        points.push_back(p);
      }
    const auto start = std::chrono::steady_clock::now();
    const std::vector<World::GroundShadowTruth> from_mesh = world.groundShadow(points, {mesh}, 0);
    const double mesh_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const std::vector<World::GroundShadowTruth> from_box = world.groundShadow(points, {analytic}, 0);
    double sum = 0.0, worst = 0.0, darkest = 1.0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double d = std::abs(luminance(from_mesh[k].hdr) - luminance(from_box[k].hdr));
      sum += d;
      worst = std::max(worst, d);
      darkest = std::min(darkest, luminance(from_box[k].hdr));
    }
    std::printf("%s: %zu points, mean |mesh - box| %.5f, worst %.5f, darkest %.3f, mesh %.0f ms\n", environment,
                points.size(), sum / points.size(), worst, darkest, mesh_ms);
    EXPECT_LT(darkest, 0.8) << "the points must include real shadow";
    EXPECT_LT(sum / points.size(), 1e-3) << environment;
    // A point in a sun's penumbra: the sun's pieces along the box's edge,
    // each decided by its centre; a 3 deg sun is ~10^4 pieces of 0.027 deg
    // (< 1e-4 of E_up each), ~110 of them along a chord, so even errors of
    // one sign stay under 5e-3 (measured: 2.2e-3).
    EXPECT_LT(worst, 5e-3) << environment;
  }
}

// The directional albedo of `material` seen from `view` (unit) on an
// upward surface, lit by `sky`: the brute-force integral of f (n.l) L over
// the upper hemisphere on a fine (theta, phi) grid.
glm::dvec3 bruteForceTopFace(const Environment& sky, const GltfSurface& material, const glm::dvec3& view) {
  constexpr int kRows = 768, kColumns = 3072;
  glm::dvec3 sum(0.0);
  for (int row = 0; row < kRows; ++row) {
    const double t0 = 0.5 * kPi * row / kRows, t1 = 0.5 * kPi * (row + 1) / kRows;
    const double theta = 0.5 * (t0 + t1);
    const double cell = (std::cos(t0) - std::cos(t1)) * 2.0 * kPi / kColumns;
    for (int column = 0; column < kColumns; ++column) {
      const double phi = 2.0 * kPi * (column + 0.5) / kColumns;
      const glm::dvec3 l(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      sum += cell * gltf_brdf::evaluate({0.0, 0.0, 1.0}, view, l, material) * sky.radiance(l);
    }
  }
  return sum;
}

// The top of a box sees only the sky, so its radiance is the integral
// above: what the frame's pixels there must show, for a rough dielectric
// and a metal, under a uniform sky (where the estimator's only error is its
// noise) and under a sun (which the sky's importance sampling must find).
TEST(MeshTruth, TheTopOfABoxShowsTheSkyIntegratedThroughItsBrdf) {
  struct Case {
    const char* environment;
    double base, metallic, roughness;
  };
  for (const Case& c : {Case{"uniform", 0.6, 0.0, 0.6}, Case{"uniform", 0.9, 1.0, 0.3}, Case{"sun_sky", 0.3, 0.0, 0.6},
                        Case{"sun_sky", 0.5, 1.0, 0.3}}) {
    SceneConfig scene = defaultScene();
    scene.environment = c.environment;
    scene.camera_path.name = "static";
    scene.noise_sigma_code = 0.0;
    const World world(scene);
    model::Material material;
    material.base_color_factor = glm::vec4(glm::vec3(static_cast<float>(c.base)), 1.0f);
    material.metallic_factor = static_cast<float>(c.metallic);
    material.roughness_factor = static_cast<float>(c.roughness);
    const glm::dvec3 size(0.06, 0.06, 0.04);
    const glm::dvec2 at(-0.10, 0.06);
    const VirtualOccluder box = boxMesh(size, at, 0.0, material);
    const glm::dvec3 top_w(at, size.z);
    const PoseCamFromWorld pose = world.pose(0);
    const glm::dvec2 pixel = projectWorldPoints(scene.camera, pose, {top_w})[0];
    // Only the box's pixels around the top's centre (the same bytes as in
    // the whole frame: AWindowRendersItsPixelsAsTheWholeFrameDoes).
    const World::PixelWindow window{static_cast<int>(pixel.x) - 8, static_cast<int>(pixel.y) - 8,
                                    static_cast<int>(pixel.x) + 9, static_cast<int>(pixel.y) + 9, true};
    ImageRGB8 frame;
    FrameTruth truth;
    const auto start = std::chrono::steady_clock::now();
    world.renderWithOccluders(0, {box}, frame, truth, &window);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

    const glm::dvec3 view = glm::normalize(pose.cameraCenterWorld() - top_w);
    GltfSurface surface;
    surface.base_color = glm::dvec3(c.base);
    surface.metallic = c.metallic;
    surface.roughness = c.roughness;
    const std::unique_ptr<Environment> sky = makeEnvironment(c.environment);
    const glm::dvec3 expected = world.exposure() * bruteForceTopFace(*sky, surface, view);
    // A 7 x 7 window around the top's centre (the top spans ~50 px).
    glm::dvec3 measured(0.0);
    int max_code = 0;
    const int cx = static_cast<int>(std::lround(pixel.x)), cy = static_cast<int>(std::lround(pixel.y));
    for (int y = cy - 3; y <= cy + 3; ++y)
      for (int x = cx - 3; x <= cx + 3; ++x)
        for (int ch = 0; ch < 3; ++ch) {
          measured[ch] += testing::pixelLinear(frame, x, y, ch) / 49.0;
          max_code = std::max<int>(max_code, frame.row(y)[3 * x + ch]);
        }
    const double relative = std::abs(luminance(measured) - luminance(expected)) / luminance(expected);
    std::printf("%s base %.1f metallic %.0f roughness %.1f: frame %.4f, integral %.4f (%.2f%%), frame %.0f ms\n",
                c.environment, c.base, c.metallic, c.roughness, luminance(measured), luminance(expected),
                100.0 * relative, ms);
    ASSERT_LT(max_code, 250) << "clipped: the comparison needs the unclipped value";
    // 49 pixels x 64 paths a corner: the estimator's noise is well under
    // 1% (uniform sky) to ~1.5% (a sun found by 1% of the sky samples'
    // floor and the BRDF's); half an 8-bit code is 0.4% at these levels.
    EXPECT_LT(relative, 0.03) << c.environment;
  }
}

// A shadow ray asks only whether the mesh is met: the BVH's any-hit
// traversal must say so exactly when the closest-hit one finds a hit, for
// rays from all around and through a model of many triangles, and through
// MASK holes (where it falls back to the closest-hit walk).
TEST(MeshTruth, ShadowRaysAgreeWithClosestHits) {
  model::Material grey;
  auto sphere = std::make_shared<const model::MeshModel>(model::sphereModel(0.03, 24, grey));
  glm::dmat4 world_from_model(1.0);
  world_from_model[3] = glm::dvec4(0.0, 0.0, 0.03, 1.0);
  const VirtualOccluder mesh = meshOccluder(sphere, world_from_model);
  ASSERT_FALSE(mesh.has_mask_material);
  std::uint64_t state = 12345;
  auto uniform = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  int hits = 0, misses = 0;
  for (int i = 0; i < 4000; ++i) {
    const glm::dvec3 origin(0.1 * (2 * uniform() - 1), 0.1 * (2 * uniform() - 1), 0.08 * uniform());
    const glm::dvec3 dir = glm::normalize(glm::dvec3(0.0, 0.0, 0.03) - origin +
                                          0.04 * glm::dvec3(2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1));
    const bool closest = intersectMesh(mesh, origin, dir, std::numeric_limits<double>::infinity()).has_value();
    ASSERT_EQ(occluderBlocks(mesh, origin, dir), closest) << i;
    (closest ? hits : misses) += 1;
    // A limit short of the hit is no hit.
    if (closest) {
      const double t = intersectMesh(mesh, origin, dir, std::numeric_limits<double>::infinity())->t;
      EXPECT_FALSE(occluderBlocks(mesh, origin, dir, 0.5 * t)) << i;
    }
  }
  EXPECT_GT(hits, 500);
  EXPECT_GT(misses, 500);
}

// A window renders its pixels as the whole frame does, and nothing else;
// with occluders_only the model's own pixels are still the same bytes
// (the floor around them black), at a fraction of the cost.
TEST(MeshTruth, AWindowRendersItsPixelsAsTheWholeFrameDoes) {
  SceneConfig scene = defaultScene();
  scene.camera_path.name = "static";
  scene.noise_sigma_code = 0.0;
  const World world(scene);
  model::Material material;
  material.base_color_factor = glm::vec4(0.5f, 0.4f, 0.3f, 1.0f);
  material.metallic_factor = 1.0f;
  material.roughness_factor = 0.4f;
  VirtualOccluder box = boxMesh({0.04, 0.04, 0.03}, {-0.10, 0.06}, 20.0, material);
  box.path_samples = 8;
  ImageRGB8 whole, windowed, only;
  FrameTruth truth;
  const auto start = std::chrono::steady_clock::now();
  world.renderWithOccluders(0, {box}, whole, truth);
  const double whole_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const glm::dvec2 at = projectWorldPoints(scene.camera, world.pose(0), {glm::dvec3(-0.10, 0.06, 0.015)})[0];
  World::PixelWindow window{static_cast<int>(at.x) - 30, static_cast<int>(at.y) - 30, static_cast<int>(at.x) + 30,
                            static_cast<int>(at.y) + 30, false};
  world.renderWithOccluders(0, {box}, windowed, truth, &window);
  window.occluders_only = true;
  const auto only_start = std::chrono::steady_clock::now();
  world.renderWithOccluders(0, {box}, only, truth, &window);
  const double only_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - only_start).count();
  const std::vector<float> floor_coverage = world.coverage(0, SceneObject::kFloor);
  int inside_differing = 0, outside_lit = 0, model_pixels = 0, model_differing = 0;
  for (int y = 0; y < whole.height; ++y)
    for (int x = 0; x < whole.width; ++x) {
      const bool in = x >= window.x_begin && x < window.x_end && y >= window.y_begin && y < window.y_end;
      for (int c = 0; c < 3; ++c) {
        const int k = 3 * x + c;
        if (in)
          inside_differing += windowed.row(y)[k] != whole.row(y)[k];
        else
          outside_lit += windowed.row(y)[k] != 0 || only.row(y)[k] != 0;
      }
      if (!in) continue;
      // The model's pixels: where the windowed frame differs from the plain
      // floor (the box hides it), and the occluders-only frame lit them.
      bool lit = false;
      for (int c = 0; c < 3; ++c) lit = lit || only.row(y)[3 * x + c] != 0;
      if (lit && floor_coverage[static_cast<size_t>(y) * whole.width + x] == 1.0f) {
        // A pixel the occluders-only frame lit, which the floor's coverage
        // (without the box) calls all floor: the box covers it, at least partly.
        ++model_pixels;
        bool same = true;
        for (int c = 0; c < 3; ++c) same = same && only.row(y)[3 * x + c] == whole.row(y)[3 * x + c];
        model_differing += same ? 0 : 1;
      }
    }
  std::printf("window 60x60: %d bytes differ from the whole frame, %d lit outside; occluders only: %d model pixels, "
              "%d differ (edges); whole %.2f s, occluders only %.2f s\n",
              inside_differing, outside_lit, model_pixels, model_differing, whole_s, only_s);
  EXPECT_EQ(inside_differing, 0);
  EXPECT_EQ(outside_lit, 0);
  EXPECT_GT(model_pixels, 500);
  // Only the outline's pixels may differ: they hold the floor's share in the whole frame.
  EXPECT_LT(model_differing, model_pixels / 4);
  EXPECT_LT(only_s, whole_s);
}

// Lit by what the 8-bit camera can know: where nothing in the ball's view
// clips (overcast), that is the full HDR world, byte for byte; in the sun
// it is less (the sun clips), and the per-pixel clip leaves the sun's pixel
// its clipped value, so a sunlit metal box's top is darker than the HDR
// truth's but not black.
TEST(MeshTruth, TheEightBitKnowableSkyIsTheHdrSkyWhereNothingClips) {
  model::Material material;
  material.base_color_factor = glm::vec4(0.6f, 0.6f, 0.6f, 1.0f);
  material.metallic_factor = 0.0f;
  material.roughness_factor = 0.7f;
  for (const char* environment : {"overcast", "sun_sky"}) {
    SceneConfig scene = defaultScene();
    scene.environment = environment;
    scene.camera_path.name = "static";
    scene.noise_sigma_code = 0.0;
    const World world(scene);
    VirtualOccluder box = boxMesh({0.05, 0.05, 0.03}, {-0.10, 0.06}, 0.0, material);
    box.path_samples = 16;
    const glm::dvec2 top = projectWorldPoints(scene.camera, world.pose(0), {glm::dvec3(-0.10, 0.06, 0.03)})[0];
    const World::PixelWindow window{static_cast<int>(top.x) - 6, static_cast<int>(top.y) - 6,
                                    static_cast<int>(top.x) + 7, static_cast<int>(top.y) + 7, true};
    ImageRGB8 hdr, knowable;
    FrameTruth truth;
    world.renderWithOccluders(0, {box}, hdr, truth, &window);
    box.clipped_lighting = true;
    world.renderWithOccluders(0, {box}, knowable, truth, &window);
    double sum_hdr = 0.0, sum_knowable = 0.0;
    int differing = 0;
    for (int y = window.y_begin; y < window.y_end; ++y)
      for (int x = window.x_begin; x < window.x_end; ++x)
        for (int c = 0; c < 3; ++c) {
          sum_hdr += testing::pixelLinear(hdr, x, y, c);
          sum_knowable += testing::pixelLinear(knowable, x, y, c);
          differing += hdr.row(y)[3 * x + c] != knowable.row(y)[3 * x + c];
        }
    std::printf("%s: the box's top, knowable / HDR = %.3f, %d bytes differ\n", environment, sum_knowable / sum_hdr,
                differing);
    if (std::string(environment) == "overcast") {
      EXPECT_EQ(differing, 0);
    } else {
      EXPECT_LT(sum_knowable, 0.8 * sum_hdr);
      EXPECT_GT(sum_knowable, 0.1 * sum_hdr);
    }
  }
}

}  // namespace
}  // namespace probelight::sim
