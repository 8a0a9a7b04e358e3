// The object's on-screen velocity and smear from the last frames
// (stages/screen_motion.hpp), and the stage that gives it to the object
// (stages/motion_match_stage.hpp): exact for steady motion and steady
// acceleration, at even and uneven frame times; unknown, not guessed,
// across a gap, a reset or a bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "stages/motion_match_stage.hpp"
#include "stages/screen_motion.hpp"

namespace probelight {
namespace {

// Positions from a parabola: p(t) = p0 + v0 t + a t^2 / 2.
glm::dvec2 parabola(double t) { return {100.0 + 300.0 * t + 0.5 * 900.0 * t * t, 50.0 - 120.0 * t - 0.5 * 400.0 * t * t}; }
glm::dvec2 parabolaVelocity(double t) { return {300.0 + 900.0 * t, -120.0 - 400.0 * t}; }

TEST(ScreenMotion, TwoFramesGiveTheirDifferenceAndThreeASteadyAccelerationExactly) {
  ScreenMotion motion;
  EXPECT_FALSE(motion.velocityPxPerS());
  motion.observe(0.0, parabola(0.0));
  EXPECT_FALSE(motion.velocityPxPerS());
  motion.observe(1.0 / 30.0, parabola(1.0 / 30.0));
  const glm::dvec2 two = *motion.velocityPxPerS();
  EXPECT_NEAR(two.x, (parabola(1.0 / 30.0).x - parabola(0.0).x) * 30.0, 1e-9);
  // Uneven steps (a dropped frame, a late one): still exact for the parabola.
  for (double t : {3.0 / 30.0, 3.5 / 30.0, 5.0 / 30.0}) {
    motion.observe(t, parabola(t));
    const glm::dvec2 v = *motion.velocityPxPerS();
    EXPECT_NEAR(v.x, parabolaVelocity(t).x, 1e-7) << t;
    EXPECT_NEAR(v.y, parabolaVelocity(t).y, 1e-7) << t;
  }
  // The smear over 10 ms: the velocity times the time.
  const glm::dvec2 smear = *motion.smearPx(0.01);
  EXPECT_NEAR(smear.x, 0.01 * parabolaVelocity(5.0 / 30.0).x, 1e-9);
  EXPECT_FALSE(motion.smearPx(0.0));
  EXPECT_FALSE(motion.smearPx(std::numeric_limits<double>::quiet_NaN()));
}

TEST(ScreenMotion, AGapAStepBackOrABadInputStartsAgain) {
  ScreenMotion motion;
  motion.observe(0.0, {0.0, 0.0});
  motion.observe(0.033, {10.0, 0.0});
  ASSERT_TRUE(motion.velocityPxPerS());
  // Frames lost for longer than a motion can be assumed steady.
  motion.observe(0.033 + ScreenMotion::kLongestGapS + 0.01, {500.0, 0.0});
  EXPECT_FALSE(motion.velocityPxPerS());
  motion.observe(0.4, {501.0, 0.0});
  ASSERT_TRUE(motion.velocityPxPerS());
  // A timestamp that does not move forward.
  motion.observe(0.4, {502.0, 0.0});
  EXPECT_FALSE(motion.velocityPxPerS());
  motion.observe(0.43, {503.0, 0.0});
  ASSERT_TRUE(motion.velocityPxPerS());
  EXPECT_NEAR(motion.velocityPxPerS()->x, 1.0 / 0.03, 1e-9);
  motion.observe(0.46, {std::numeric_limits<double>::infinity(), 0.0});
  EXPECT_FALSE(motion.velocityPxPerS());
  motion.observe(0.49, {503.0, 0.0});
  EXPECT_FALSE(motion.velocityPxPerS());
  motion.forget();
  EXPECT_FALSE(motion.smearPx(0.01));
}

// The stage: a tag sliding sideways past a still camera at a steady speed.
class MotionMatch : public ::testing::Test {
 protected:
  MotionMatch() {
    camera_.width_px = 640;
    camera_.height_px = 480;
    camera_.fx_px = camera_.fy_px = 600.0;
    camera_.cx_px = 320.0;
    camera_.cy_px = 240.0;
    config_.motion_blur = true;
  }
  // The world slid by x_m along +X in front of a camera 0.5 m above it,
  // looking straight down (x_cam = x_w, y_cam = -y_w, z_cam = 0.5 - z_w).
  tracking::TagTrackResult trackAt(double x_m) const {
    tracking::TagTrackResult track;
    track.found = true;
    track.pose.R_cam_from_world = glm::dmat3(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
    track.pose.t_cam_from_world = {x_m, 0.0, 0.5};
    return track;
  }
  CameraIntrinsics camera_;
  CameraMatchConfig config_;
  RunReport report_;
};

TEST_F(MotionMatch, ASteadySlideIsSmearedByItsSpeedTimesTheExposureAndSaysWhyNot) {
  MotionMatchStage stage(config_, camera_, glm::dvec3(0.0, 0.0, 0.03), report_);
  FrameMetadata metadata;
  metadata.exposure_us = 8000.0;
  // 0.3 m/s at 0.47 m from the camera: 600 * 0.3 / 0.47 = 383 px/s, 3.06 px in 8 ms.
  const double speed_m_per_s = 0.3, depth_m = 0.47;
  for (int frame = 0; frame < 5; ++frame) stage.run(trackAt(speed_m_per_s * frame / 30.0), metadata, frame / 30.0);
  ASSERT_TRUE(stage.smearPx());
  EXPECT_NEAR(stage.smearPx()->x, 600.0 * speed_m_per_s / depth_m * 0.008, 1e-6);
  EXPECT_NEAR(stage.smearPx()->y, 0.0, 1e-9);
  const nlohmann::json json = report_.toJson(1, 1.0);
  EXPECT_EQ(json["stages"]["match_motion"]["runs"], 4);
  EXPECT_EQ(json["stages"]["match_motion"]["skip_reasons"]["no_previous_frame"], 1);

  // Unknown exposure time, a lost tag, a still camera: no smear, each with its reason.
  FrameMetadata unknown;
  stage.run(trackAt(speed_m_per_s * 5 / 30.0), unknown, 5 / 30.0);
  EXPECT_FALSE(stage.smearPx());
  stage.run(tracking::TagTrackResult{}, metadata, 6 / 30.0);
  EXPECT_FALSE(stage.smearPx());
  for (int frame = 7; frame < 10; ++frame) stage.run(trackAt(0.2), metadata, frame / 30.0);
  EXPECT_FALSE(stage.smearPx());
  const nlohmann::json after = report_.toJson(1, 1.0);
  EXPECT_EQ(after["stages"]["match_motion"]["skip_reasons"]["unknown_exposure_time"], 1);
  EXPECT_EQ(after["stages"]["match_motion"]["skip_reasons"]["no_tag"], 1);
  EXPECT_EQ(after["stages"]["match_motion"]["skip_reasons"]["no_previous_frame"], 2);
  EXPECT_EQ(after["stages"]["match_motion"]["skip_reasons"]["still"], 2);
}

TEST_F(MotionMatch, OffSkipsEveryFrame) {
  config_.motion_blur = false;
  MotionMatchStage stage(config_, camera_, glm::dvec3(0.0), report_);
  FrameMetadata metadata;
  metadata.exposure_us = 8000.0;
  for (int frame = 0; frame < 3; ++frame) stage.run(trackAt(0.01 * frame), metadata, frame / 30.0);
  EXPECT_FALSE(stage.smearPx());
  EXPECT_EQ(report_.toJson(1, 1.0)["stages"]["match_motion"]["skip_reasons"]["off"], 3);
}

}  // namespace
}  // namespace probelight
