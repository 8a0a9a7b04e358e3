// No blind spot (issue 18): the probe gathered over the views a moving
// camera passes through (ibl/probe_accumulator, ibl/probe_observation),
// against the simulator's truth, beside what one view gives.
//
// Each world is turned so that its brightest light lies behind the ball as
// the path's first view sees it (its azimuth; a script lamp is placed
// there at 10 deg elevation): the case single-view methods lose. Each view
// is rendered at EV 0 and bracketed (EV -3, -6, ... until the ball stops
// clipping), merged direction by direction as `run` merges
// (ibl::bracketToCubeMap), observed with its confidences and the frame
// around the ball, and added to the probe. Figures: the mean relative
// luminance error of the irradiance at analyze's 14 normals
//  - with brackets, against the full-HDR truth: the probe after every view
//    of the path, and each view alone (the single-view method);
//  - without brackets (8-bit frames), against the truth an 8-bit camera
//    can know through the ball (World::irradiance's clipped).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdlib.h>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "accuracy_test_support.hpp"
#include "app/analyze.hpp"
#include "capture/rgb_image_io.hpp"
#include "config/camera_file.hpp"
#include "config/rig_file.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/probe_accumulator.hpp"
#include "ibl/probe_observation.hpp"
#include "ibl/probe_outline.hpp"
#include "ibl/probe_to_cube.hpp"
#include "sim/camera_path.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

using testing::luminance;

glm::dvec3 fromAzimuthElevationDeg(double azimuth_deg, double elevation_deg) {
  const double a = glm::radians(azimuth_deg), e = glm::radians(elevation_deg);
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

double azimuthDeg(const glm::dvec3& d) { return glm::degrees(std::atan2(d.y, d.x)); }

struct WorldCase {
  const char* label;
  std::string environment;
  bool script_lamp = false;  // a soft box of the lighting script, behind the ball
};

struct PathCase {
  const char* label;
  sim::CameraPathConfig path;
  std::vector<std::uint64_t> frames;
};

std::vector<PathCase> pathCases() {
  std::vector<PathCase> cases;
  sim::CameraPathConfig base;
  base.distance_m = 0.55;
  base.elevation_deg = 25.0;  // low: the blind spot's neighbourhood reaches the horizon's lights
  base.azimuth_start_deg = -90.0;
  {
    // Walking around the rig at 15 deg/s: 8 views over 3.5 s.
    PathCase orbit{"orbit", base, {}};
    orbit.path.name = "orbit";
    orbit.path.azimuth_rate_deg_per_frame = -0.5;
    for (int i = 0; i < 8; ++i) orbit.frames.push_back(15u * i);
    cases.push_back(orbit);
  }
  {
    // Holding still (+-2 deg): 8 views over 8 s.
    PathCase wobble{"slow_wobble", base, {}};
    wobble.path.name = "slow_wobble";
    for (int i = 0; i < 8; ++i) wobble.frames.push_back(30u * i);
    cases.push_back(wobble);
  }
  {
    // Independent views around the rig (sim::RandomPoseGenerator).
    PathCase random{"random", base, {}};
    random.path.name = "random";
    for (int i = 0; i < 8; ++i) random.frames.push_back(i);
    cases.push_back(random);
  }
  {
    // One sweep of the arm, +-35 deg in 3 s: 8 views along it.
    PathCase sweep{"hand_held_sweep", base, {}};
    sweep.path.name = "hand_held_sweep";
    for (int i = 0; i < 8; ++i) sweep.frames.push_back(13u * i);
    cases.push_back(sweep);
  }
  return cases;
}

// The brightest direction of the world's sky (upper hemisphere, 1 deg).
glm::dvec3 brightestSkyDirection(const sim::World& world) {
  glm::dvec3 best(0.0, 0.0, 1.0);
  double peak = -1.0;
  for (int e = 0; e < 90; ++e)
    for (int a = 0; a < 360; ++a) {
      const glm::dvec3 d = fromAzimuthElevationDeg(a + 0.5, e + 0.5);
      const double lum = luminance(world.radiance(d, 0).hdr);
      if (lum > peak) {
        peak = lum;
        best = d;
      }
    }
  return best;
}

struct ViewFigures {
  double bracket_single = 0.0;  // this view's bracket alone, vs HDR truth
  double ldr_single = 0.0;      // this view's 8-bit map alone, vs clipped truth
};

struct CaseFigures {
  std::vector<ViewFigures> views;
  double bracket_probe = 0.0;  // all views accumulated, vs HDR truth
  double ldr_probe = 0.0;      // 8-bit views accumulated, vs clipped truth
  double blind_share = 0.0;    // of all light, within 25 deg of the first view's blind direction
  double seen_fraction = 0.0;  // of the sphere, in the bracketed probe
  long frame_texels = 0;       // texels the frame around the ball gave, over the views
  double ms_per_view = 0.0;    // observe + accumulate, CPU, per view (bracketed)
};

template <typename Truth, typename Estimate>
double meanIrradianceError(const Truth& truth, const Estimate& estimate) {
  double sum = 0.0;
  for (const glm::dvec3& normal : analysisNormals()) {
    const double expected = luminance(truth(normal));
    sum += std::abs(luminance(estimate(normal)) - expected) / expected;
  }
  return sum / 14.0;
}

// The world of `world_case` seen along `path`, its brightest light turned
// to where the ball hides it from the view of `first_frame`; `blind_w` that
// direction (from the ball, away from that view's eye).
sim::SceneConfig sceneWithLightBehindTheBall(const WorldCase& world_case, const sim::CameraPathConfig& path,
                                             std::uint64_t first_frame, glm::dvec3& blind_w) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.environment = world_case.environment;
  scene.camera_path = path;
  const glm::dvec3 first_eye = sim::makeCameraPath(scene)->pose(first_frame).cameraCenterWorld();
  blind_w = glm::normalize(scene.rig.probe_center_w - first_eye);
  if (world_case.script_lamp) {
    scene.lighting.lamp_on_frame = 0;
    scene.lighting.lamp_azimuth_deg = azimuthDeg(blind_w);
    scene.lighting.lamp_elevation_deg = 10.0;
    scene.lighting.lamp_width_deg = 12.0;
    scene.lighting.lamp_height_deg = 12.0;
  } else {
    const sim::World unturned(scene);
    scene.environment_rotation_deg = azimuthDeg(blind_w) - azimuthDeg(brightestSkyDirection(unturned));
  }
  return scene;
}

CaseFigures runCase(const WorldCase& world_case, const PathCase& path_case) {
  glm::dvec3 blind_w;
  const sim::SceneConfig scene = sceneWithLightBehindTheBall(world_case, path_case.path, path_case.frames.front(), blind_w);
  const sim::World world(scene);

  CaseFigures figures;
  {
    double total = 0.0, blind = 0.0;
    for (int e = -89; e < 90; e += 2)
      for (int a = 0; a < 360; a += 2) {
        const glm::dvec3 d = fromAzimuthElevationDeg(a, e);
        const double lum = luminance(world.radiance(d, 0).hdr) * std::cos(glm::radians(static_cast<double>(e)));
        total += lum;
        if (glm::dot(d, blind_w) > std::cos(glm::radians(25.0))) blind += lum;
      }
    figures.blind_share = blind / total;
  }

  const ibl::HdrMergeSettings merge;
  const double clip_level = ibl::clippedMapLevel(merge, scene.rig.probe_reflectance);
  ibl::ProbeAccumulatorSettings accumulator_settings;
  accumulator_settings.noise.probe_reflectance = scene.rig.probe_reflectance;
  accumulator_settings.noise.clip_level = clip_level;
  ibl::ProbeAccumulator bracketed(accumulator_settings), eight_bit(accumulator_settings);
  const ibl::ObservationSettings observation_settings;
  RigGeometry rig = scene.rig;
  rig.post_radius_m = scene.post_radius_m;  // the rig's measured post

  auto hdrTruth = [&](const glm::dvec3& n) { return world.irradiance(n, 0).hdr; };
  auto clippedTruth = [&](const glm::dvec3& n) { return world.irradiance(n, 0).clipped; };
  double accumulate_ms = 0.0;
  for (const std::uint64_t frame : path_case.frames) {
    ImageRGB8 reference;
    FrameTruth truth;
    world.render(frame, reference, truth);
    EXPECT_TRUE(truth.probe_fully_visible && truth.tag_fully_visible) << path_case.label << " frame " << frame;
    const tracking::TagTrackResult track = testing::trackRendered(scene, reference);
    if (!track.found) {
      ADD_FAILURE() << world_case.label << " " << path_case.label << " frame " << frame << ": " << track.status;
      continue;
    }
    const ibl::MirrorBallView ball{scene.camera, track.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
    const ibl::ProbeOutline outline = ibl::computeProbeOutline(ball);
    std::vector<ImageRGB8> images;
    std::vector<double> evs;
    testing::renderBracketUntilBallUnclipped(world, frame, reference, outline, merge.clip_code, images, evs);
    std::vector<ibl::BracketView> bracket;
    for (size_t i = 0; i < images.size(); ++i) bracket.push_back({&images[i], evs[i], ball});
    ibl::ProbeToCubeParams params;
    params.face_size = 64;
    params.probe_reflectance = scene.rig.probe_reflectance;
    const ibl::CubeMapRGB ldr_cube = ibl::probeImageToCubeMap(ball, reference, params);
    params.samples_per_axis = 4;
    std::vector<std::uint8_t> still_clipped;
    const ibl::CubeMapRGB hdr_cube = ibl::bracketToCubeMap(bracket, merge, params, &still_clipped);

    ViewFigures view;
    view.bracket_single = meanIrradianceError(hdrTruth, [&](const glm::dvec3& n) { return ibl::irradianceFromCubeMap(hdr_cube, n); });
    view.ldr_single = meanIrradianceError(clippedTruth, [&](const glm::dvec3& n) { return ibl::irradianceFromCubeMap(ldr_cube, n); });
    figures.views.push_back(view);

    // The frame around the ball, at the reference exposure (camera linear:
    // the map's units, the ball's reflectance already divided out there).
    const ibl::LinearPixelReader read = [&](int x, int y, bool& clipped) {
      const std::uint8_t* p = reference.row(y) + 3 * x;
      clipped = std::max({p[0], p[1], p[2]}) >= merge.clip_code;
      return glm::dvec3(ibl::srgbToLinear(p[0] / 255.0), ibl::srgbToLinear(p[1] / 255.0),
                        ibl::srgbToLinear(p[2] / 255.0));
    };
    const auto start = std::chrono::steady_clock::now();
    ibl::ProbeObservation observed = ibl::observeBall(ball, hdr_cube, nullptr, &still_clipped, clip_level, observation_settings);
    figures.frame_texels += ibl::addFrameAroundBall(observed, ball, rig, read, observation_settings);
    bracketed.add(observed);
    accumulate_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    ibl::ProbeObservation observed_8bit = ibl::observeBall(ball, ldr_cube, nullptr, nullptr, clip_level, observation_settings);
    ibl::addFrameAroundBall(observed_8bit, ball, rig, read, observation_settings);
    eight_bit.add(observed_8bit);
  }
  figures.ms_per_view = accumulate_ms / std::max<size_t>(1, figures.views.size());
  const ibl::CubeMapRGB probe = bracketed.radianceMap();
  const ibl::CubeMapRGB probe_8bit = eight_bit.radianceMap(static_cast<float>(clip_level));
  figures.bracket_probe = meanIrradianceError(hdrTruth, [&](const glm::dvec3& n) { return ibl::irradianceFromCubeMap(probe, n); });
  figures.ldr_probe = meanIrradianceError(clippedTruth, [&](const glm::dvec3& n) { return ibl::irradianceFromCubeMap(probe_8bit, n); });
  figures.seen_fraction = bracketed.seenSolidAngleFraction();
  return figures;
}

TEST(MultiViewAccuracy, TheProbeGatheredOverAPathHasNoBlindSpot) {
  const std::vector<WorldCase> worlds = {
      {"sunrise", "sunrise"},
      {"night_street", "night_street"},
      {"studio + lamp", "studio", true},
      {"sun_sky", "sun_sky"},
      {"overcast", "overcast"},
      {"Kerner (real)", std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/KernerEnvLatLong.exr"},
      {"Stage (real)", std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/StageEnvLatLong.exr"},
  };
  std::printf("\n| world | path | blind share | bracketed: probe / first view / mean view / worst view | "
              "8-bit: probe / first view / mean view | seen | frame texels | ms a view (CPU, with its own visibility test) |\n|---|---|---|---|---|---|---|---|\n");
  double probe_sum = 0.0, single_sum = 0.0, ldr_probe_sum = 0.0, ldr_single_sum = 0.0, worst_probe = 0.0;
  std::string worst_case;
  int cases = 0, views = 0;
  for (const WorldCase& world_case : worlds)
    for (const PathCase& path_case : pathCases()) {
      const CaseFigures figures = runCase(world_case, path_case);
      ASSERT_FALSE(figures.views.empty());
      double view_mean = 0.0, view_worst = 0.0, ldr_view_mean = 0.0;
      for (const ViewFigures& view : figures.views) {
        view_mean += view.bracket_single / figures.views.size();
        view_worst = std::max(view_worst, view.bracket_single);
        ldr_view_mean += view.ldr_single / figures.views.size();
        single_sum += view.bracket_single;
        ldr_single_sum += view.ldr_single;
        ++views;
      }
      std::printf("| %s | %s | %.2f | %.1f%% / %.1f%% / %.1f%% / %.1f%% | %.1f%% / %.1f%% / %.1f%% | %.3f | %ld | %.1f |\n",
                  world_case.label, path_case.label, figures.blind_share, 100.0 * figures.bracket_probe,
                  100.0 * figures.views.front().bracket_single, 100.0 * view_mean, 100.0 * view_worst,
                  100.0 * figures.ldr_probe, 100.0 * figures.views.front().ldr_single, 100.0 * ldr_view_mean,
                  figures.seen_fraction, figures.frame_texels, figures.ms_per_view);
      std::fflush(stdout);
      probe_sum += figures.bracket_probe;
      ldr_probe_sum += figures.ldr_probe;
      ++cases;
      if (figures.bracket_probe > worst_probe) {
        worst_probe = figures.bracket_probe;
        worst_case = std::string(world_case.label) + " " + path_case.label;
      }
    }
  const double probe_mean = probe_sum / cases, single_mean = single_sum / views;
  const double ldr_probe_mean = ldr_probe_sum / cases, ldr_single_mean = ldr_single_sum / views;
  std::printf("\nbracketed: probe mean %.2f%%, worst %.2f%% (%s); single views mean %.2f%%\n"
              "8-bit: probe mean %.2f%%; single views mean %.2f%%\n",
              100.0 * probe_mean, 100.0 * worst_probe, worst_case.c_str(), 100.0 * single_mean,
              100.0 * ldr_probe_mean, 100.0 * ldr_single_mean);
  // The bounds.
  EXPECT_LE(probe_mean, 0.03);
  EXPECT_LE(worst_probe, 0.08) << worst_case;
  // Without brackets: no worse than one view.
  EXPECT_LE(ldr_probe_mean, ldr_single_mean);
}

// Four still photos of the rig from anywhere around it (sim::RandomPoseGenerator's
// views 0..3), each with its own bracket, given to `probelight analyze` as
// four --frame flags: analysis.json's irradiance against the same truths and
// bounds. Without brackets (--no-white-ref: the maps as the ball shows
// them) the merged views are held to each view analysed alone.
TEST(MultiViewAccuracy, FourStillViewsGivenToAnalyze) {
  const std::vector<WorldCase> worlds = {
      {"sunrise", "sunrise"},
      {"night_street", "night_street"},
      {"studio + lamp", "studio", true},
      {"Kerner (real)", std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/KernerEnvLatLong.exr"},
      {"Stage (real)", std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/StageEnvLatLong.exr"},
  };
  char dir_template[] = "/tmp/probelight_four_views_XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  const std::filesystem::path dir(dir_template);
  sim::CameraPathConfig path;
  path.name = "random";
  const std::vector<std::uint64_t> frames = {0, 1, 2, 3};

  auto readIrradiance = [](const std::filesystem::path& out, const char* key) {
    std::ifstream in(out / "analysis.json");
    const nlohmann::json analysis = nlohmann::json::parse(in);
    std::vector<std::pair<glm::dvec3, glm::dvec3>> entries;
    for (const auto& entry : analysis.at(key))
      entries.push_back({glm::dvec3(entry.at("normal")[0], entry.at("normal")[1], entry.at("normal")[2]),
                         glm::dvec3(entry.at("rgb")[0], entry.at("rgb")[1], entry.at("rgb")[2])});
    return entries;
  };
  auto errorAgainst = [](const std::vector<std::pair<glm::dvec3, glm::dvec3>>& entries, const auto& truth) {
    double sum = 0.0;
    for (const auto& [normal, rgb] : entries) {
      const double expected = luminance(truth(normal));
      sum += std::abs(luminance(rgb) - expected) / expected;
    }
    return entries.empty() ? 1.0 : sum / entries.size();
  };
  auto analyze = [&](const AnalyzeOptions& options) {
    std::ostringstream log;
    const Status status = runAnalyze(options, log);
    EXPECT_TRUE(status.isOk()) << status.message() << "\n" << log.str();
  };

  std::printf("\n| world | bracketed: 4 views / view alone (mean, worst) | 8-bit: 4 views / view alone (mean) |\n|---|---|---|\n");
  double bracketed_sum = 0.0, bracketed_worst = 0.0, ldr_sum = 0.0, ldr_single_sum = 0.0, single_sum = 0.0;
  int single_count = 0;
  for (const WorldCase& world_case : worlds) {
    glm::dvec3 blind_w;
    const sim::SceneConfig scene = sceneWithLightBehindTheBall(world_case, path, frames.front(), blind_w);
    const sim::World world(scene);
    config::saveCameraFile((dir / "camera.yaml").string(), scene.camera);
    RigGeometry rig = scene.rig;
    rig.post_radius_m = scene.post_radius_m;
    config::saveRigFile((dir / "rig.yaml").string(), rig);
    AnalyzeOptions bracketed, eight_bit;
    for (AnalyzeOptions* options : {&bracketed, &eight_bit}) {
      options->camera_path = (dir / "camera.yaml").string();
      options->rig_path = (dir / "rig.yaml").string();
    }
    bracketed.out_dir = (dir / "bracketed").string();
    eight_bit.out_dir = (dir / "eight_bit").string();
    eight_bit.white_reference = false;
    std::vector<AnalyzeOptions> alone;
    for (const std::uint64_t frame : frames) {
      ImageRGB8 reference;
      FrameTruth truth;
      world.render(frame, reference, truth);
      ASSERT_TRUE(truth.probe_fully_visible && truth.tag_fully_visible) << world_case.label << " " << frame;
      const tracking::TagTrackResult track = testing::trackRendered(scene, reference);
      ASSERT_TRUE(track.found) << track.status;
      const ibl::MirrorBallView ball{scene.camera, track.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
      std::vector<ImageRGB8> images;
      std::vector<double> evs;
      testing::renderBracketUntilBallUnclipped(world, frame, reference, ibl::computeProbeOutline(ball),
                                               ibl::HdrMergeSettings{}.clip_code, images, evs);
      AnalyzeView view;
      for (std::size_t i = 0; i < images.size(); ++i) {
        const std::string name = "view" + std::to_string(frame) + "_ev" + std::to_string(static_cast<int>(evs[i])) + ".png";
        std::string error;
        ASSERT_TRUE(writeRgbPng((dir / name).string(), images[i], error)) << error;
        if (i == 0)
          view.frame_path = (dir / name).string();
        else
          view.brackets.push_back({(dir / name).string(), evs[i], false});
      }
      if (bracketed.frame_path.empty()) {
        bracketed.frame_path = eight_bit.frame_path = view.frame_path;
        bracketed.brackets = view.brackets;
      } else {
        bracketed.more_views.push_back(view);
        eight_bit.more_views.push_back({view.frame_path, {}});
      }
      AnalyzeOptions one = eight_bit;
      one.frame_path = view.frame_path;
      one.more_views.clear();
      one.out_dir = (dir / ("alone" + std::to_string(frame))).string();
      AnalyzeOptions one_bracketed = one;
      one_bracketed.brackets = view.brackets;
      one_bracketed.white_reference = true;
      one_bracketed.out_dir += "_bracketed";
      alone.push_back(one);
      alone.push_back(one_bracketed);
    }
    auto hdrTruth = [&](const glm::dvec3& n) { return world.irradiance(n, 0).hdr; };
    auto clippedTruth = [&](const glm::dvec3& n) { return world.irradiance(n, 0).clipped; };
    analyze(bracketed);
    analyze(eight_bit);
    const double bracketed_error = errorAgainst(readIrradiance(bracketed.out_dir, "irradiance"), hdrTruth);
    const double ldr_error = errorAgainst(readIrradiance(eight_bit.out_dir, "irradiance"), clippedTruth);
    double single_mean = 0.0, single_worst = 0.0, ldr_single_mean = 0.0;
    for (std::size_t i = 0; i < alone.size(); i += 2) {
      analyze(alone[i]);
      analyze(alone[i + 1]);
      const double ldr = errorAgainst(readIrradiance(alone[i].out_dir, "irradiance"), clippedTruth);
      const double hdr = errorAgainst(readIrradiance(alone[i + 1].out_dir, "irradiance"), hdrTruth);
      ldr_single_mean += ldr / frames.size();
      single_mean += hdr / frames.size();
      single_worst = std::max(single_worst, hdr);
      ldr_single_sum += ldr;
      single_sum += hdr;
      ++single_count;
    }
    std::printf("| %s | %.1f%% / %.1f%%, %.1f%% | %.1f%% / %.1f%% |\n", world_case.label, 100.0 * bracketed_error,
                100.0 * single_mean, 100.0 * single_worst, 100.0 * ldr_error, 100.0 * ldr_single_mean);
    std::fflush(stdout);
    bracketed_sum += bracketed_error;
    bracketed_worst = std::max(bracketed_worst, bracketed_error);
    ldr_sum += ldr_error;
  }
  const double bracketed_mean = bracketed_sum / worlds.size(), ldr_mean = ldr_sum / worlds.size();
  const double ldr_single_mean = ldr_single_sum / single_count;
  std::printf("\nanalyze, four views: bracketed mean %.2f%%, worst %.2f%% (views alone %.2f%%); 8-bit mean %.2f%% "
              "(views alone %.2f%%)\n",
              100.0 * bracketed_mean, 100.0 * bracketed_worst, 100.0 * single_sum / single_count, 100.0 * ldr_mean,
              100.0 * ldr_single_mean);
  EXPECT_LE(bracketed_mean, 0.03);
  EXPECT_LE(bracketed_worst, 0.08);
  EXPECT_LE(ldr_mean, ldr_single_mean);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace probelight
