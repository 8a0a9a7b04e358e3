// Seed D's exposure for the virtual lamp (stages/lamp_exposure.hpp): the
// brightest region's mean from an integral image equals the brute-force
// scan; the gain keeps the lit frame's brightest region where the room's
// was (or at 90% of white); and the ramp moves in stops with its time
// constant.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "stages/lamp_exposure.hpp"

namespace probelight {
namespace {

TEST(LampExposure, TheBrightestWindowIsTheBruteForceScans) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat blocks(30, 40, CV_64F);
  for (int y = 0; y < blocks.rows; ++y)
    for (int x = 0; x < blocks.cols; ++x) blocks.at<double>(y, x) = unit(rng);
  blocks.at<double>(12, 17) = 30.0;  // one hot block
  for (int window : {1, 3, 5, 40}) {
    double brute = 0.0;
    const int w = std::min(window, blocks.cols), h = std::min(window, blocks.rows);
    for (int y = 0; y + h <= blocks.rows; ++y)
      for (int x = 0; x + w <= blocks.cols; ++x) {
        double sum = 0.0;
        for (int j = 0; j < h; ++j)
          for (int i = 0; i < w; ++i) sum += blocks.at<double>(y + j, x + i);
        brute = std::max(brute, sum / (w * h));
      }
    EXPECT_NEAR(brightestWindowMean(blocks, window), brute, 1e-9) << window;
  }
  EXPECT_EQ(brightestWindowMean(cv::Mat(), 4), 0.0);
}

TEST(LampExposure, OnlyTheLampsOwnLightPastWhiteDarkensTheFrame) {
  // Under white with the lamp: nothing to do.
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, 0.8, 0.9), 1.0);
  // The lamp takes a region to 1.8: back to 0.9.
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, 1.8, 0.9), 0.5);
  // A window already at white without the lamp sets the level kept.
  EXPECT_DOUBLE_EQ(lampExposureTarget(1.2, 1.5, 0.9), 0.8);
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, 0.0, 0.9), 1.0);
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, std::nan(""), 0.9), 1.0);
}

TEST(LampExposure, TheRampMovesInStopsWithItsTimeConstant) {
  ExposureRamp ramp(0.5);
  EXPECT_DOUBLE_EQ(ramp.gain(), 1.0);
  // One time constant toward 1/4 (2 stops down): 1 - 1/e of the stops.
  ramp.moveToward(0.25, 0.5);
  EXPECT_NEAR(std::log2(ramp.gain()), -2.0 * (1.0 - std::exp(-1.0)), 1e-12);
  // Many small steps make the same path as one large one.
  ExposureRamp stepped(0.5);
  for (int i = 0; i < 50; ++i) stepped.moveToward(0.25, 0.01);
  EXPECT_NEAR(stepped.gain(), ramp.gain(), 1e-12);
  // A bad step or target leaves it.
  const double before = ramp.gain();
  ramp.moveToward(0.25, -1.0);
  ramp.moveToward(std::nan(""), 0.1);
  ramp.moveToward(0.0, 0.1);
  EXPECT_DOUBLE_EQ(ramp.gain(), before);
}

}  // namespace
}  // namespace probelight

namespace probelight {
namespace {

// The stage on a white floor seen straight down from 0.4 m with a lamp
// 5 cm above it: the lamp would take the floor past white, so the gain
// ramps down; with the lamp no longer drawn (no tag) it ramps back to 1.
TEST(LampExposureStage, DarkensWhileTheLampWouldClipAndRecoversWithoutIt) {
  CameraIntrinsics camera;
  camera.width_px = 160;
  camera.height_px = 120;
  camera.fx_px = camera.fy_px = 150.0;
  camera.cx_px = 79.5;
  camera.cy_px = 59.5;
  PoseCamFromWorld pose;  // looking down: x_cam = x_w, y_cam = -y_w, z_cam = 0.4 - z_w
  pose.R_cam_from_world = glm::dmat3(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
  pose.t_cam_from_world = {0.0, 0.0, 0.4};
  FrameBuffer frame;
  frame.rgb.resize(camera.width_px, camera.height_px);
  std::fill(frame.rgb.pixels.begin(), frame.rgb.pixels.end(), std::uint8_t{200});  // 0.58 linear
  frame.finishRgb();
  ibl::VirtualLamp lamp;
  lamp.position_w = {0.0, 0.0, 0.05};
  lamp.colour = glm::dvec3(1.0);
  lamp.intensity = 0.01;  // 4x the room's light straight below
  RunReport report;
  LampExposureStage stage(true, lamp, camera, ibl::CameraTransfer{}, report);
  const std::optional<glm::dvec3> room = glm::dvec3(1.0);
  double time_s = 0.0;
  stage.run(true, pose, frame, room, time_s);
  EXPECT_DOUBLE_EQ(stage.gain(), 1.0);  // the first lit frame is shown as it was: the ramp starts
  for (int i = 0; i < 60; ++i) stage.run(true, pose, frame, room, time_s += 1.0 / 30.0);
  const double darkened = stage.gain();
  const double target = report.extra["virtual_lamp"]["exposure"]["target"].get<double>();
  EXPECT_LT(target, 0.5);
  // Two seconds, four time constants: within 2% of the target's stops.
  EXPECT_NEAR(std::log2(darkened), std::log2(target), 0.02 * std::abs(std::log2(target)));
  for (int i = 0; i < 60; ++i) stage.run(false, pose, frame, room, time_s += 1.0 / 30.0);
  EXPECT_NEAR(std::log2(stage.gain()), 0.0, 0.02 * std::abs(std::log2(target)));
  const nlohmann::json json = report.toJson(121, 4.0);
  EXPECT_EQ(json["stages"]["lamp_exposure"]["runs"], 61);
  EXPECT_EQ(json["stages"]["lamp_exposure"]["skip_reasons"]["no_object"], 60);
}

}  // namespace
}  // namespace probelight
