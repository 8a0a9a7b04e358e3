// The ground shadow of the whole path (tag -> pose -> GPU reflection map ->
// dome of lights -> GPU shadow maps and ground fraction) against the
// simulator's brute-force truth (World::groundShadow), for a sphere and a box
// beside the tag, in a sky-lit, a sunny, a studio and a real sunny world,
// with all three light placements. And the dominant light against the true
// sun.
//
// The measure is the fraction of the ground's light that arrives, (E - R) / E,
// on the ground around the object (out to 4 bounding radii from its middle,
// its own footprint left out: the object hides it). The reference that can be
// met from one 8-bit frame is the truth of the clipped environment; the full
// HDR truth is printed beside it: what the 8-bit frame costs (a later issue).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "accuracy_test_support.hpp"
#include "stages/bracket_merge.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/light_dome.hpp"
#include "model/generated_models.hpp"
#include "model/gltf_loader.hpp"
#include "model/model_placement.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "sim/camera_path.hpp"
#include "sim/occluder.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "stages/scene_object.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

using testing::luminance;

struct Object {
  const char* name;
  sim::VirtualOccluder truth;
  ibl::ShadowCaster caster;
  double bound = 0.05;  // on the worst MAE against the clipped truth, in the bounded worlds
};

// A user's model as both sides see it: the kiosk's caster (its triangles,
// as stages/scene_object places them) and the simulator's ray-traced copy.
Object meshObject(const char* name, std::shared_ptr<const model::MeshModel> mesh, const glm::dvec2& position_w,
                  double size_m, double yaw_deg) {
  model::ModelPlacement placement;
  placement.position_m = position_w;
  placement.yaw_rad = glm::radians(yaw_deg);
  const glm::vec3 extent = mesh->max_m - mesh->min_m;
  placement.scale = size_m / std::max({extent.x, extent.y, extent.z});
  const SceneObject placed = modelSceneObject(mesh, placement);
  // Issue 16's bound for a mesh's ground shadow.
  return {name, sim::meshOccluder(mesh, placed.world_from_model), placed.shape, 0.03};
}

std::vector<Object> objects() {
  // Beside the tag, on the floor, on the side away from the ball.
  Object sphere{"sphere", {}, {}};
  sphere.truth.position_w = {-0.10, 0.06};
  sphere.truth.radius_m = 0.035;
  sphere.caster.position_w = sphere.truth.position_w;
  sphere.caster.radius_m = sphere.truth.radius_m;
  Object box{"box", {}, {}};
  box.truth.shape = sim::VirtualOccluder::Shape::kBox;
  box.truth.position_w = {-0.10, -0.05};
  box.truth.box_size_m = {0.05, 0.04, 0.07};
  box.truth.box_yaw_deg = 25.0;
  box.caster.shape = ibl::ShadowCaster::Shape::kBox;
  box.caster.position_w = box.truth.position_w;
  box.caster.box_size_m = box.truth.box_size_m;
  box.caster.box_yaw_rad = glm::radians(box.truth.box_yaw_deg);
  std::vector<Object> all = {sphere, box};
  // Issue 16: a user's model. A concave one (a bowl: light passes over its
  // rim into the hollow, which a bounding shape would miss) and a corpus
  // file, turned.
  model::Material grey;
  all.push_back(meshObject("bowl mesh", std::make_shared<const model::MeshModel>(model::bowlModel(0.5, 0.06, 12, grey)),
                           {-0.10, 0.06}, 0.09, 0.0));
  auto textured = std::make_shared<model::MeshModel>();
  std::string error;
  if (model::loadGltfModel("/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf", {}, *textured, error))
    all.push_back(meshObject("BoxTextured mesh", textured, {-0.10, -0.05}, 0.06, 25.0));
  else
    ADD_FAILURE() << error;
  return all;
}

// The fraction the GPU stage gives at ground point p: bilinear in its texture,
// 1 outside the square it covers (no shadow reaches there).
double gpuFractionAt(const passes::GroundShadow& shadow, const std::vector<glm::vec3>& fraction, const glm::dvec2& p) {
  const ibl::GroundRegion& region = shadow.region();
  const int n = shadow.groundTextureSizePx();
  const glm::dvec2 uv = (p - region.centre_w) / (2.0 * region.half_size_m) + 0.5;
  if (uv.x < 0.0 || uv.y < 0.0 || uv.x > 1.0 || uv.y > 1.0) return 1.0;
  const double x = std::clamp(uv.x * n - 0.5, 0.0, n - 1.0), y = std::clamp(uv.y * n - 0.5, 0.0, n - 1.0);
  const int x0 = std::min(static_cast<int>(x), n - 2), y0 = std::min(static_cast<int>(y), n - 2);
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int i, int j) { return luminance(glm::dvec3(fraction[static_cast<std::size_t>(j) * n + i])); };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// Ground points around the object: a 40 x 40 grid over +-4 bounding radii,
// outside its footprint.
std::vector<glm::dvec2> pointsAround(const ibl::ShadowCaster& caster) {
  std::vector<glm::dvec2> points;
  const double reach = 4.0 * caster.boundingRadius();
  const glm::dvec2 centre = caster.position_w;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const glm::dvec2 p = centre + reach * glm::dvec2((2.0 * i + 1.0) / 40.0 - 1.0, (2.0 * j + 1.0) / 40.0 - 1.0);
      // Under the object: a ray straight up meets it.
      if (caster.intersect(glm::dvec3(p, 1e-6), {0.0, 0.0, 1.0})) continue;
      points.push_back(p);
    }
  return points;
}

struct Row {
  double mae_clipped = 0.0, mae_hdr = 0.0, darkest_truth = 1.0, darkest_gpu = 1.0;
};

class ShadowAccuracy : public testing::GpuSuite {};

TEST_F(ShadowAccuracy, GroundAttenuationAgainstTheTruthAndTheDominantLightAgainstTheSun) {
  struct World {
    std::string name, environment;
    bool bounded;  // the bound applies (a sky-lit and a sunny world)
  };
  const std::string data = PROBELIGHT_TEST_DATA_DIR;
  const std::vector<World> worlds = {{"overcast", "overcast", true},
                                     {"sun_sky", "sun_sky", true},
                                     {"studio", "studio", false},
                                     {"Kerner (real, sunny)", data + "/env/KernerEnvLatLong.exr", false}};
  const ibl::DomePlacement placements[] = {ibl::DomePlacement::kFixedRegions, ibl::DomePlacement::kMedianCut,
                                           ibl::DomePlacement::kClustered};
  const gles::Capabilities capabilities = gles::probeCapabilities();
  std::printf("\n| world | object | placement | MAE vs clipped truth | MAE vs HDR truth | darkest: truth (clipped) / ours |\n"
              "|---|---|---|---|---|---|\n");
  const std::vector<Object> scene_objects = objects();
  std::map<std::pair<ibl::DomePlacement, std::size_t>, double> worst_bounded;
  for (const World& world_case : worlds) {
    sim::SceneConfig scene = sim::defaultScene();
    scene.environment = world_case.environment;
    scene.rig.probe_reflectance = 0.7;  // chrome: the clip level sits at 1 / 0.7 in the map
    scene.camera_path.name = "static";
    const sim::World world(scene);
    ImageRGB8 frame;
    FrameTruth truth;
    world.render(0, frame, truth);
    ASSERT_TRUE(truth.probe_fully_visible && truth.tag_fully_visible) << world_case.name;

    std::vector<std::uint8_t> luma;
    lumaFromRgb(frame, luma);
    tracking::TagDetectorSettings detector;
    tracking::TagTracker tracker(detector, scene.rig, scene.camera);
    const tracking::TagTrackResult track = tracker.track(luma.data(), frame.width, frame.height, frame.width);
    ASSERT_TRUE(track.found) << track.status;
    std::string error;
    passes::CameraFrameTexture texture;
    ASSERT_TRUE(texture.init(capabilities, error) && texture.upload(frame, error)) << error;
    passes::EnvironmentMapSettings map_settings;
    map_settings.glossy_levels = 0;
    passes::EnvironmentMaps maps;
    ASSERT_TRUE(maps.init(capabilities, map_settings, error)) << error;
    const ibl::MirrorBallView ball{scene.camera, track.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
    ASSERT_TRUE(maps.updateReflection(texture, ball, scene.rig.probe_reflectance, error)) << error;
    std::vector<float> validity;
    const std::optional<ibl::CubeMapRGB> reflection = maps.readReflection(error, &validity);
    ASSERT_TRUE(reflection) << error;

    passes::GroundShadow shadow;
    ASSERT_TRUE(shadow.init(capabilities, {}, error)) << error;
    // The truth does not depend on the kiosk's light placement: once an object.
    std::vector<std::vector<glm::dvec2>> points_by_object;
    std::vector<std::vector<sim::World::GroundShadowTruth>> truth_by_object;
    for (const Object& object : scene_objects) {
      points_by_object.push_back(pointsAround(object.caster));
      truth_by_object.push_back(world.groundShadow(points_by_object.back(), {object.truth}, 0));
    }
    for (const ibl::DomePlacement placement : placements) {
      ibl::LightDomeSettings dome_settings;
      dome_settings.placement = placement;
      const std::vector<ibl::DomeLight> dome = ibl::fitLightDome(*reflection, &validity, dome_settings);
      const std::vector<ibl::ShadowLight> lights = ibl::groundShadowLights(dome);
      for (std::size_t o = 0; o < scene_objects.size(); ++o) {
        const Object& object = scene_objects[o];
        ASSERT_TRUE(shadow.update(lights, object.caster, error)) << error;
        const auto fraction = shadow.readFraction(error);
        ASSERT_TRUE(fraction) << error;
        const std::vector<glm::dvec2>& points = points_by_object[o];
        const std::vector<sim::World::GroundShadowTruth>& expected = truth_by_object[o];
        Row row;
        for (std::size_t k = 0; k < points.size(); ++k) {
          const double ours = gpuFractionAt(shadow, *fraction, points[k]);
          const double clipped = luminance(expected[k].clipped), hdr = luminance(expected[k].hdr);
          row.mae_clipped += std::abs(ours - clipped) / points.size();
          row.mae_hdr += std::abs(ours - hdr) / points.size();
          row.darkest_truth = std::min(row.darkest_truth, clipped);
          row.darkest_gpu = std::min(row.darkest_gpu, ours);
        }
        std::printf("| %s | %s | %s | %.3f | %.3f | %.2f / %.2f |\n", world_case.name.c_str(), object.name,
                    ibl::toString(placement), row.mae_clipped, row.mae_hdr, row.darkest_truth, row.darkest_gpu);
        if (world_case.bounded) {
          double& worst = worst_bounded[{placement, o}];
          worst = std::max(worst, row.mae_clipped);
        }
      }
    }

    // The dominant light against the sun (the brightest direction of the
    // true HDR sky), in the sunny worlds.
    if (world_case.environment == "sun_sky" || world_case.environment.find("Kerner") != std::string::npos) {
      glm::dvec3 sun(0.0);
      double brightest = -1.0;
      for (int row = 0; row < 360; ++row)
        for (int column = 0; column < 1440; ++column) {
          const double e = 0.5 * M_PI * (row + 0.5) / 360.0, a = 2.0 * M_PI * (column + 0.5) / 1440.0;
          const glm::dvec3 d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
          const double L = luminance(world.radiance(d, 0).hdr);
          if (L > brightest) {
            brightest = L;
            sun = d;
          }
        }
      const std::vector<ibl::DomeLight> dome = ibl::fitLightDome(*reflection, &validity);
      const ibl::DominantLight dominant =
          ibl::findDominantLight(*reflection, &validity, dome, 1.0 / scene.rig.probe_reflectance);
      const double error_deg = glm::degrees(std::acos(std::clamp(glm::dot(dominant.direction_w, sun), -1.0, 1.0)));
      std::printf("\n[ dominant ] %s: %.1f deg from the true sun (%s, clipped blob %.3f sr)\n", world_case.name.c_str(),
                  error_deg, dominant.from_clipped_region ? "centre of the clipped blob" : "peak radiance",
                  dominant.clipped_solid_angle_sr);
      ASSERT_TRUE(dominant.found);
      // The simulated sun clips in a small blob around itself: its centre is
      // the sun to within the ball's resolution (~2 degrees a pixel here).
      // The real sky's clipped blob is large and lopsided; its figure is
      // reported, not bounded: the later HDR issue brings brackets.
      if (world_case.environment == "sun_sky") {
        EXPECT_LT(error_deg, 5.0);
      }
    }
  }
  // The issues' bounds: MAE <= 0.05 in the sky-lit and the sunny world,
  // against what the 8-bit frame can know, for every placement (issue 4);
  // <= 0.03 for a mesh (issue 16).
  for (const auto& [key, worst] : worst_bounded)
    EXPECT_LE(worst, scene_objects[key.second].bound) << ibl::toString(key.first) << ", " << scene_objects[key.second].name;
}

// Issue 7: with an exposure bracket, the shadow against the full-HDR truth.
// The simulated camera takes the same view at EV 0, -3, -6, ... until the
// ball stops clipping; the frames are merged as `run` merges its own
// (stages/bracket_merge.hpp), the dome (clustered, the default) is fitted from
// the HDR map, and the GPU's ground fraction is compared with
// World::groundShadow's HDR truth. The 8-bit frame's figure beside it.
TEST_F(ShadowAccuracy, WithABracketTheShadowMatchesTheHdrTruth) {
  const std::string data = PROBELIGHT_TEST_DATA_DIR;
  const std::vector<std::pair<std::string, std::string>> worlds = {
      {"sun_sky", "sun_sky"},
      {"studio", "studio"},
      {"Kerner (real)", data + "/env/KernerEnvLatLong.exr"},
      {"Stage (real)", data + "/env/StageEnvLatLong.exr"}};
  const gles::Capabilities capabilities = gles::probeCapabilities();
  std::printf("\n| world | object | bracket EVs | MAE vs HDR truth: bracket / 8-bit |\n|---|---|---|---|\n");
  double sum_bracket = 0.0, sum_ldr = 0.0, worst_bracket = 0.0;
  int rows = 0;
  for (const auto& [name, environment] : worlds) {
    sim::SceneConfig scene = sim::defaultScene();
    scene.environment = environment;
    scene.rig.probe_reflectance = 0.7;
    scene.camera_path.name = "static";
    const sim::World world(scene);
    ImageRGB8 frame;
    FrameTruth truth;
    world.render(0, frame, truth);
    std::vector<std::uint8_t> luma;
    lumaFromRgb(frame, luma);
    tracking::TagTracker tracker(tracking::TagDetectorSettings{}, scene.rig, scene.camera);
    const tracking::TagTrackResult track = tracker.track(luma.data(), frame.width, frame.height, frame.width);
    ASSERT_TRUE(track.found) << track.status;
    const ibl::MirrorBallView ball{scene.camera, track.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
    const ibl::ProbeOutline outline = ibl::computeProbeOutline(ball);

    std::string error;
    passes::CameraFrameTexture texture;
    ASSERT_TRUE(texture.init(capabilities, error) && texture.upload(frame, error)) << error;
    passes::EnvironmentMapSettings map_settings;
    map_settings.glossy_levels = 0;
    passes::EnvironmentMaps maps;
    ASSERT_TRUE(maps.init(capabilities, map_settings, error)) << error;
    ASSERT_TRUE(maps.updateReflection(texture, ball, scene.rig.probe_reflectance, error)) << error;
    std::vector<float> validity;
    const std::optional<ibl::CubeMapRGB> reflection = maps.readReflection(error, &validity);
    ASSERT_TRUE(reflection) << error;

    // The bracket, as the kiosk takes it.
    const ibl::HdrMergeSettings merge;
    std::vector<BracketCandidate> candidates;
    std::string evs = "0";
    const ImageRGB8* last = &frame;
    for (double ev = -3.0; ev >= -15.0 && ballPixelCodes(*last, outline, merge).clipped > 0; ev -= 3.0) {
      BracketCandidate candidate{"EV " + std::to_string(static_cast<int>(ev)), ev, {}};
      FrameTruth ignored;
      world.render(0, candidate.rgb, ignored, ev);
      candidates.push_back(std::move(candidate));
      last = &candidates.back().rgb;
      evs += ", " + std::to_string(static_cast<int>(ev));
    }
    const BracketSetup setup{ball, outline, scene.rig, tracking::TagDetectorSettings{}, merge, reflection->face_size};
    const BracketMergeResult merged = mergeBracketProbe(frame, std::move(candidates), setup, nullptr);
    ASSERT_TRUE(merged.hdr_cube) << merged.status << " " << merged.frames.dump();

    passes::GroundShadow shadow;
    ASSERT_TRUE(shadow.init(capabilities, {}, error)) << error;
    const std::vector<ibl::DomeLight> dome_hdr = ibl::fitLightDome(*merged.hdr_cube, &validity, {});
    const std::vector<ibl::DomeLight> dome_ldr = ibl::fitLightDome(*reflection, &validity, {});
    for (const Object& object : objects()) {
      const std::vector<glm::dvec2> points = pointsAround(object.caster);
      const std::vector<sim::World::GroundShadowTruth> expected = world.groundShadow(points, {object.truth}, 0);
      double mae[2] = {0.0, 0.0};
      for (int k = 0; k < 2; ++k) {
        ASSERT_TRUE(shadow.update(ibl::groundShadowLights(k == 0 ? dome_hdr : dome_ldr), object.caster, error)) << error;
        const auto fraction = shadow.readFraction(error);
        ASSERT_TRUE(fraction) << error;
        for (std::size_t i = 0; i < points.size(); ++i)
          mae[k] += std::abs(gpuFractionAt(shadow, *fraction, points[i]) - luminance(expected[i].hdr)) / points.size();
      }
      std::printf("| %s | %s | %s | %.3f / %.3f |\n", name.c_str(), object.name, evs.c_str(), mae[0], mae[1]);
      sum_bracket += mae[0];
      sum_ldr += mae[1];
      worst_bracket = std::max(worst_bracket, mae[0]);
      ++rows;
    }
  }
  std::printf("\nmean MAE vs HDR over %d rows: bracket %.3f, 8-bit %.3f; worst with a bracket %.3f\n", rows,
              sum_bracket / rows, sum_ldr / rows, worst_bracket);
  // The bound, for every world and object.
  EXPECT_LE(worst_bracket, 0.03);
}

}  // namespace
}  // namespace probelight
