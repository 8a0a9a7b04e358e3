// Pose and ball-outline accuracy of TagTracker on the simulated world, against
// its truth: rotation, translation, the ball outline computed from the pose
// (ibl::computeProbeOutline, which given the TRUE pose agrees with the
// simulator within 0.05 px, so what is measured here is the pose's error), and
// the corners' bias. Frames: the random pose generator (a third grazing at
// 20-25 deg elevation, a third nearly fronto-parallel) and the default orbit,
// 640x480 with the simulator's sensor noise (sigma 1.5 codes) and pixels
// integrated over their area where an edge crosses them.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ibl/probe_outline.hpp"
#include "sim/world.hpp"
#include "tag_rendering.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

// The targets. Why they are reachable, from the noise and the geometry: with
// sensor noise of 1.5 codes on an edge step of ~100-150 codes, one edge sample
// is located to ~0.02 px; each tag edge is fitted from 8-64 samples, so a
// corner is known to ~0.01 px from noise, and what remains is systematic
// (anti-aliasing, distortion). A ball ~0.14 m from the tag centre at 0.45-0.75 m
// moves by about (lever / tag half-size) times the tag corners' error, i.e.
// ~3x: 0.5 px at the ball allows ~0.15 px at the corners, the accuracy that
// the line fit reaches with margin; the rotation bound 0.3 deg is that
// corner error over a 60-200 px tag (atan(0.15 / 50) = 0.17 deg) with margin
// for grazing views, where depth is poorly constrained.
constexpr double kMaxRotationDeg = 0.3;
constexpr double kMaxTranslationRelative = 0.005;
constexpr double kMaxProbeCentrePx = 0.5;
constexpr double kMaxProbeRadiusPx = 0.5;

struct FrameSample {
  ImageRGB8 image;
  FrameTruth truth;
  std::string label;
};

std::vector<FrameSample> renderFrames(sim::SceneConfig scene, const std::string& path,
                                      const std::vector<std::uint64_t>& indices) {
  scene.camera_path.name = path;
  sim::World world(scene);
  std::vector<FrameSample> frames;
  for (std::uint64_t index : indices) {
    FrameSample frame;
    world.render(index, frame.image, frame.truth);
    frame.label = path + " " + std::to_string(index);
    frames.push_back(std::move(frame));
  }
  return frames;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}
double maximum(const std::vector<double>& values) {
  return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}

struct Errors {
  std::vector<double> rotation_deg, translation_rel, centre_px, radius_px, corner_px, track_ms;
  // Corner bias: the signed error along the direction from the true quad's
  // centre to the corner (> 0: the detected quad is too big), and the mean
  // signed x / y error. Noise averages out over frames and corners; a mean
  // well away from 0 is a bias of the edge localisation.
  std::vector<double> corner_outward_px, corner_dx_px, corner_dy_px;
  int missed = 0;
};

Errors measure(const sim::SceneConfig& scene, const std::vector<FrameSample>& frames, bool refine_corners) {
  tracking::TagDetectorSettings settings;
  settings.family = scene.rig.tag_family;
  settings.refine_corners = refine_corners;
  Errors errors;
  std::vector<std::uint8_t> luma;
  auto world_corners = tracking::tagCornersWorld(scene.rig.tag_size_m);
  for (const FrameSample& frame : frames) {
    // A fresh tracker per frame: these views are unrelated, so no history.
    tracking::TagTracker tracker(settings, scene.rig, scene.camera);
    lumaFromRgb(frame.image, luma);
    auto start = std::chrono::steady_clock::now();
    tracking::TagTrackResult result = tracker.track(luma.data(), frame.image.width, frame.image.height, frame.image.width);
    errors.track_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    if (!result.found) {
      ++errors.missed;
      ADD_FAILURE() << frame.label << ": " << result.status;
      continue;
    }
    const PoseCamFromWorld& truth = frame.truth.pose;
    errors.rotation_deg.push_back(tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, truth.R_cam_from_world));
    errors.translation_rel.push_back(glm::length(result.pose.t_cam_from_world - truth.t_cam_from_world) /
                                     glm::length(truth.t_cam_from_world));
    ibl::ProbeOutline outline = ibl::computeProbeOutline(
        ibl::MirrorBallView{scene.camera, result.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m});
    errors.centre_px.push_back(glm::length(outline.center_px - frame.truth.probe_center_px));
    errors.radius_px.push_back(std::abs(outline.radius_px - frame.truth.probe_radius_px));
    if (std::getenv("PROBELIGHT_POSE_DETAIL")) {
      glm::dvec3 normal_cam = truth.R_cam_from_world * glm::dvec3(0, 0, 1);
      glm::dvec3 to_tag = glm::normalize(truth.t_cam_from_world);
      std::printf("  %-12s view %.1f deg off normal, dist %.2f m: rot %.3f deg, centre %.3f px, reproj %.3f, alt %.3f%s\n",
                  frame.label.c_str(), glm::degrees(std::acos(std::abs(glm::dot(normal_cam, to_tag)))),
                  glm::length(truth.t_cam_from_world), errors.rotation_deg.back(), errors.centre_px.back(),
                  result.reprojection_error_px, result.alternative_reprojection_error_px,
                  result.pose_ambiguous ? " ambiguous" : "");
    }

    std::vector<glm::dvec2> true_corners =
        testing::projectWorldPoints({world_corners.begin(), world_corners.end()}, truth, scene.camera);
    glm::dvec2 centre(0.0);
    for (const glm::dvec2& c : true_corners) centre += 0.25 * c;
    for (std::size_t k = 0; k < 4; ++k) {
      glm::dvec2 error = result.corners_px[k] - true_corners[k];
      errors.corner_px.push_back(glm::length(error));
      errors.corner_outward_px.push_back(glm::dot(error, glm::normalize(true_corners[k] - centre)));
      errors.corner_dx_px.push_back(error.x);
      errors.corner_dy_px.push_back(error.y);
    }
  }
  return errors;
}

double mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

void print(const char* name, const Errors& e) {
  std::printf(
      "[ accuracy ] %-26s rotation %.3f / %.3f deg, translation %.3f / %.3f %%, ball centre %.3f / %.3f px, "
      "radius %.3f / %.3f px (median / max)\n"
      "[ accuracy ] %-26s corners %.3f / %.3f px; mean signed: outward %+.3f px, x %+.3f, y %+.3f px; "
      "track %.2f ms median; missed %d\n",
      name, median(e.rotation_deg), maximum(e.rotation_deg), 100 * median(e.translation_rel),
      100 * maximum(e.translation_rel), median(e.centre_px), maximum(e.centre_px), median(e.radius_px),
      maximum(e.radius_px), name, median(e.corner_px), maximum(e.corner_px), mean(e.corner_outward_px),
      mean(e.corner_dx_px), mean(e.corner_dy_px), median(e.track_ms), e.missed);
}

void expectTargets(const Errors& e, const std::string& name) {
  SCOPED_TRACE(name);
  EXPECT_EQ(e.missed, 0);
  EXPECT_LE(maximum(e.rotation_deg), kMaxRotationDeg);
  EXPECT_LE(maximum(e.translation_rel), kMaxTranslationRelative);
  EXPECT_LE(maximum(e.centre_px), kMaxProbeCentrePx);
  EXPECT_LE(maximum(e.radius_px), kMaxProbeRadiusPx);
  // No bias left: the outward mean over >= 80 corners would sit within a few
  // hundredths of a pixel of 0 if the edges were found without bias (the
  // sRGB-luma gradient put it near -0.1 px before, the dark quad shrunk).
  EXPECT_LE(std::abs(mean(e.corner_outward_px)), 0.05);
}

std::vector<std::uint64_t> range(std::uint64_t first, std::uint64_t count, std::uint64_t step) {
  std::vector<std::uint64_t> indices;
  for (std::uint64_t i = 0; i < count; ++i) indices.push_back(first + i * step);
  return indices;
}

TEST(PoseAccuracy, RandomViewsIncludingGrazingAndFrontoParallelMeetTheTargets) {
  sim::SceneConfig scene = sim::defaultScene();
  // 24 views: 8 grazing (20-25 deg elevation), 8 nearly fronto-parallel, 8 between.
  std::vector<FrameSample> frames = renderFrames(scene, "random", range(0, 24, 1));
  Errors before = measure(scene, frames, false);
  Errors after = measure(scene, frames, true);
  print("random, detector corners", before);
  print("random, refined corners", after);
  expectTargets(after, "random");
}

TEST(PoseAccuracy, DefaultOrbitMeetsTheTargets) {
  sim::SceneConfig scene = sim::defaultScene();
  // 20 frames over the orbit's 230 deg sweep (0.2 deg a frame).
  std::vector<FrameSample> frames = renderFrames(scene, "orbit", range(0, 20, 57));
  Errors before = measure(scene, frames, false);
  Errors after = measure(scene, frames, true);
  print("orbit, detector corners", before);
  print("orbit, refined corners", after);
  expectTargets(after, "orbit");
}

// At the orbit's start the tag is upright in the image, so every tag edge runs
// within a degree or two of the pixel grid, and the tag's cells (12.5 px
// here) put every grid edge at the same sub-pixel phase: nothing averages an
// edge-placement bias out. Point-sampled pixels (the simulator's regular 2x2
// samples alone) put such edges in half-pixel steps, which cost 0.56 px at
// the ball and 0.4 px at the corners; the simulator now integrates edge
// pixels over their area as a sensor does, and the targets hold here too.
TEST(PoseAccuracy, OrbitStartWithEdgesAlongThePixelGrid) {
  sim::SceneConfig scene = sim::defaultScene();
  std::vector<FrameSample> frames = renderFrames(scene, "orbit", range(0, 20, 1));
  Errors before = measure(scene, frames, false);
  Errors after = measure(scene, frames, true);
  print("orbit start, detector", before);
  print("orbit start, refined", after);
  expectTargets(after, "orbit start");
  EXPECT_LE(median(after.centre_px), median(before.centre_px));
}

// Near fronto-parallel the two planar solutions fit the corners about equally
// well; over a slow hand-held-like path the tracker must never jump to the
// other one. A flip shows as the chosen pose being farther from the truth
// than the alternative (when there still is one), and as a rotation error of
// about twice the view's angle off the tag normal (the mirrored solution
// reflects the normal about the line of sight): 6 to 14 deg on this path.
// Every frame must also meet the rotation target, which is 20x below the
// smallest flip; this path's roll crosses 0, so it includes tag edges
// parallel to the pixel grid.
TEST(PoseAccuracy, SlowNearFrontoParallelPathNeverFlips) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.camera_path.name = "slow_wobble";
  scene.camera_path.look_at_w = glm::dvec3(0.0);  // the tag centre on the optical axis
  scene.camera_path.elevation_deg = 85.0;         // +-2 deg wobble: 3-7 deg off the tag normal
  sim::World world(scene);
  tracking::TagDetectorSettings settings;
  settings.family = scene.rig.tag_family;
  tracking::TagTracker tracker(settings, scene.rig, scene.camera);
  std::vector<std::uint8_t> luma;
  int ambiguous = 0, flips = 0;
  std::vector<double> rotation_deg;
  constexpr int kFrames = 60;  // 2 s at 30 fps: the wobble's slowest term turns by ~100 deg
  for (int frame = 0; frame < kFrames; ++frame) {
    ImageRGB8 image;
    FrameTruth truth;
    world.render(static_cast<std::uint64_t>(frame), image, truth);
    lumaFromRgb(image, luma);
    tracking::TagTrackResult result = tracker.track(luma.data(), image.width, image.height, image.width);
    ASSERT_TRUE(result.found) << "frame " << frame << ": " << result.status;
    double error = tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, truth.pose.R_cam_from_world);
    rotation_deg.push_back(error);
    if (result.pose_ambiguous) ++ambiguous;
    if (std::getenv("PROBELIGHT_POSE_DETAIL"))
      std::printf("  frame %2d: rot %.3f deg, reproj %.3f, alt %.3f (%.3f deg from truth)%s\n", frame, error,
                  result.reprojection_error_px, result.alternative_reprojection_error_px,
                  result.alternative_pose ? tracking::rotationDifferenceDeg(result.alternative_pose->R_cam_from_world,
                                                                            truth.pose.R_cam_from_world)
                                          : -1.0,
                  result.pose_ambiguous ? " ambiguous" : "");
    if (result.alternative_pose) {
      double alternative_error =
          tracking::rotationDifferenceDeg(result.alternative_pose->R_cam_from_world, truth.pose.R_cam_from_world);
      double apart = tracking::rotationDifferenceDeg(result.pose.R_cam_from_world,
                                                     result.alternative_pose->R_cam_from_world);
      if (alternative_error < error && apart > 2 * kMaxRotationDeg) {
        ++flips;
        ADD_FAILURE() << "frame " << frame << " flipped: error " << error << " deg, the other solution's "
                      << alternative_error << " deg";
      }
    }
  }
  std::printf("[ no-flip  ] slow_wobble at 85 deg: %d frames, %d ambiguous, %d flips; rotation %.3f / %.3f deg\n",
              kFrames, ambiguous, flips, median(rotation_deg), maximum(rotation_deg));
  EXPECT_EQ(flips, 0);
  EXPECT_LE(maximum(rotation_deg), kMaxRotationDeg);
}

// A still camera with sensor noise (fresh each frame) keeps its corner
// refinement on most frames, and then still meets the targets; a frame
// that keeps one must be one where the tag really stayed put: its true
// corners within refinement_reuse_px of those of the frame that was
// refined, plus the detector corners' own jitter (sigma 0.01-0.06 px
// measured on this scene, so 0.15 px is over 2.5 sigma of the worst
// coordinate). On the slow wobble (the tag moves ~0.2-1 px a frame) and the
// orbit nearly every frame refines.
TEST(PoseAccuracy, AStillTagKeepsItsRefinementAndAMovedOneIsRefined) {
  tracking::TagDetectorSettings settings;
  const double allowed_shift_px = settings.refinement_reuse_px + 0.15;
  for (const std::string path : {"static", "slow_wobble", "orbit"}) {
    sim::SceneConfig scene = sim::defaultScene();
    scene.camera_path.name = path;
    sim::World world(scene);
    settings.family = scene.rig.tag_family;
    tracking::TagTracker tracker(settings, scene.rig, scene.camera);
    const auto world_corners = tracking::tagCornersWorld(scene.rig.tag_size_m);
    std::vector<std::uint8_t> luma;
    std::vector<glm::dvec2> refined_true_corners;
    std::vector<double> rotation_deg, centre_px;
    int reused = 0, frames = 40, drifted = 0;
    for (int frame = 0; frame < frames; ++frame) {
      ImageRGB8 image;
      FrameTruth truth;
      world.render(static_cast<std::uint64_t>(frame), image, truth);
      lumaFromRgb(image, luma);
      const tracking::TagTrackResult result = tracker.track(luma.data(), image.width, image.height, image.width);
      ASSERT_TRUE(result.found) << path << " frame " << frame << ": " << result.status;
      const std::vector<glm::dvec2> true_corners =
          testing::projectWorldPoints({world_corners.begin(), world_corners.end()}, truth.pose, scene.camera);
      if (result.refinement_reused) {
        ++reused;
        ASSERT_FALSE(refined_true_corners.empty()) << path << " frame " << frame << " reused before any refinement";
        for (std::size_t k = 0; k < 4; ++k)
          if (glm::length(true_corners[k] - refined_true_corners[k]) > allowed_shift_px) ++drifted;
      } else {
        refined_true_corners = true_corners;
      }
      rotation_deg.push_back(tracking::rotationDifferenceDeg(result.pose.R_cam_from_world, truth.pose.R_cam_from_world));
      const ibl::ProbeOutline outline = ibl::computeProbeOutline(
          ibl::MirrorBallView{scene.camera, result.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m});
      centre_px.push_back(glm::length(outline.center_px - truth.probe_center_px));
    }
    std::printf("[ reuse    ] %-11s %d of %d frames kept their refinement; rotation %.3f / %.3f deg, ball centre %.3f / %.3f px\n",
                path.c_str(), reused, frames, median(rotation_deg), maximum(rotation_deg), median(centre_px),
                maximum(centre_px));
    EXPECT_EQ(drifted, 0) << path;
    EXPECT_LE(maximum(rotation_deg), kMaxRotationDeg) << path;
    EXPECT_LE(maximum(centre_px), kMaxProbeCentrePx) << path;
    if (path == "static") {
      EXPECT_GE(reused, frames * 3 / 4) << "a still camera should mostly skip the refinement";
    }
    if (path == "orbit") {
      EXPECT_LE(reused, frames / 10) << "a moving camera refines";
    }
  }
}

}  // namespace
}  // namespace probelight
