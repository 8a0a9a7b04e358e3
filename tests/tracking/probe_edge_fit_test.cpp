// Refining the ball's outline against the image: with a correct rig it must
// stay put, and with a rig measured wrong by millimetres (the usual error of
// a tape measure) it must find the ball's true outline in the frame.
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "ibl/probe_outline.hpp"
#include "sim/world.hpp"
#include "tracking/probe_edge_fit.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

struct Case {
  const char* what;
  glm::dvec3 centre_error_m;
  double radius_error_m;
};

TEST(ProbeEdgeFit, FindsTheTrueOutlineWhenTheRigIsMeasuredWrong) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.environment = "studio";
  scene.camera_path.name = "random";
  scene.rig.probe_reflectance = 0.7;  // chrome; a perfect mirror has no step at its rim
  sim::World world(scene);
  const ibl::CameraTransfer srgb;
  const Case cases[] = {{"exact rig", {0, 0, 0}, 0.0},
                        {"centre 3 mm off in x, 2 in z", {0.003, 0.0, 0.002}, 0.0},
                        {"centre 2 mm off in y", {0.0, -0.002, 0.0}, 0.0},
                        {"radius 2 mm too big", {0, 0, 0}, 0.002}};
  for (const Case& c : cases) {
    for (std::uint64_t frame = 0; frame < 6; ++frame) {
      ImageRGB8 image;
      FrameTruth truth;
      world.render(frame, image, truth);
      if (!truth.probe_fully_visible) continue;
      std::vector<std::uint8_t> luma;
      lumaFromRgb(image, luma);
      // The true pose, so that what is measured is the fit, not the tracker.
      const ibl::ProbeOutline predicted = ibl::computeProbeOutline(ibl::MirrorBallView{
          scene.camera, truth.pose, scene.rig.probe_center_w + c.centre_error_m, scene.rig.probe_radius_m + c.radius_error_m});
      const tracking::ProbeEdgeFit fit = tracking::fitProbeOutlineToEdges(
          luma.data(), image.width, image.height, image.width, predicted, scene.rig.probe_reflectance, srgb);
      const double before = glm::length(predicted.center_px - truth.probe_center_px);
      const double before_radius = std::abs(predicted.radius_px - truth.probe_radius_px);
      std::printf("[ edge fit ] %-30s frame %llu: centre %.3f -> %.3f px, radius %.3f -> %.3f px, "
                  "%d/%d profiles, rms %.3f px%s\n",
                  c.what, static_cast<unsigned long long>(frame), before,
                  fit.ok ? glm::length(fit.center_px - truth.probe_center_px) : -1.0, before_radius,
                  fit.ok ? std::abs(fit.radius_px - truth.probe_radius_px) : -1.0, fit.trusted_profiles, fit.profiles,
                  fit.rms_px, fit.ok ? "" : (" FAILED: " + fit.reason).c_str());
      ASSERT_TRUE(fit.ok) << c.what << " frame " << frame << ": " << fit.reason;
      // Measured: 0.02-0.28 px from the truth, whatever the rig's error.
      // The residual is the model's, not noise: the rim shows the background
      // just behind the ball only in the limit, and a quarter pixel inside it
      // the ball already reflects light from centimetres away, so the
      // half-step crossing lands a few tenths of a pixel off, by an amount
      // that depends on the view. That is why the refinement is off unless
      // asked for (a correct rig is exact) and the kiosk averages it over
      // views. 0.35 px stays inside the 0.5 px target.
      EXPECT_LT(glm::length(fit.center_px - truth.probe_center_px), 0.35) << c.what << " frame " << frame;
      EXPECT_LT(std::abs(fit.radius_px - truth.probe_radius_px), 0.35) << c.what << " frame " << frame;
    }
  }
}

TEST(ProbeEdgeFit, RefusesFramesWithoutEdgesAndBadInput) {
  sim::SceneConfig scene = sim::defaultScene();
  const sim::World world(scene);
  const FrameTruth truth = world.truth(0);
  const ibl::ProbeOutline predicted = ibl::computeProbeOutline(
      ibl::MirrorBallView{scene.camera, truth.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m});
  ASSERT_TRUE(predicted.valid);
  const ibl::CameraTransfer srgb;
  std::vector<std::uint8_t> grey(640 * 480, 128);
  tracking::ProbeEdgeFit flat = tracking::fitProbeOutlineToEdges(grey.data(), 640, 480, 640, predicted, 0.7, srgb);
  EXPECT_FALSE(flat.ok);
  EXPECT_NE(flat.reason.find("too few clear edge profiles"), std::string::npos) << flat.reason;
  EXPECT_FALSE(tracking::fitProbeOutlineToEdges(nullptr, 640, 480, 640, predicted, 0.7, srgb).ok);
  EXPECT_FALSE(tracking::fitProbeOutlineToEdges(grey.data(), 640, 480, 640, ibl::ProbeOutline{}, 0.7, srgb).ok);
  EXPECT_FALSE(tracking::fitProbeOutlineToEdges(grey.data(), 640, 480, 640, predicted, 1.0, srgb).ok);
}

TEST(ProbeEdgeFit, ImageShiftBecomesAWorldMoveThatReproducesIt) {
  sim::SceneConfig scene = sim::defaultScene();
  const sim::World world(scene);
  const PoseCamFromWorld pose = world.truth(0).pose;
  const glm::dvec2 shift(2.0, -1.5);
  const glm::dvec3 moved = tracking::probeCenterForImageShift(pose, scene.camera, scene.rig.probe_center_w, shift);
  auto project = [&](const glm::dvec3& p) {
    glm::dvec3 c = pose.toCamera(p);
    return glm::dvec2(scene.camera.fx_px * c.x / c.z, scene.camera.fy_px * c.y / c.z);
  };
  // Pinhole and perpendicular to the line of sight at the ball's depth: exact.
  const glm::dvec2 moved_px = project(moved) - project(scene.rig.probe_center_w);
  EXPECT_NEAR(moved_px.x, shift.x, 1e-9);
  EXPECT_NEAR(moved_px.y, shift.y, 1e-9);
  EXPECT_NEAR(pose.toCamera(moved).z, pose.toCamera(scene.rig.probe_center_w).z, 1e-12);
}

}  // namespace
}  // namespace probelight
