// The simulator's truth for a user's model: its ground shadow against the
// analytic box's, and its path-traced radiance against brute-force
// integrals of the same BRDF over the sky (which the path tracer reaches by
// importance sampling, shadow rays and multiple importance sampling).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

#include "model/generated_models.hpp"
#include "sim/environment.hpp"
#include "sim/gltf_brdf.hpp"
#include "sim/occluder.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

constexpr double kPi = std::numbers::pi;

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
    ImageRGB8 frame;
    FrameTruth truth;
    const auto start = std::chrono::steady_clock::now();
    world.renderWithOccluders(0, {box}, frame, truth);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

    const glm::dvec3 top_w(at, size.z);
    const PoseCamFromWorld pose = world.pose(0);
    const glm::dvec2 pixel = projectWorldPoints(scene.camera, pose, {top_w})[0];
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

}  // namespace
}  // namespace probelight::sim
