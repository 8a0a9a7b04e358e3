// The simulated shutter open while the camera moves (World::render's
// shutter_frames): the camera's linear light averaged over its poses
// along the path across the exposure. Measured as the lens blur is
// (lens_blur_test.cpp): on the tag's edge seen square-on, the camera
// panning about its own vertical axis so that the edge's image slides
// along the rows. A box of the edge's on-screen path L adds L^2 / 12 to
// the edge's spread, L taken from the path's poses at the shutter's
// opening and closing, not from the renderer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "sim/camera_path.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

SceneConfig panningSquareOnScene() {
  SceneConfig scene = defaultScene();
  scene.camera.distortion = {0, 0, 0, 0, 0};
  scene.camera_path.name = "pan";
  scene.camera_path.look_at_w = glm::dvec3(0.0);
  scene.camera_path.elevation_deg = 89.9;
  scene.camera_path.azimuth_start_deg = -90.0;
  scene.noise_sigma_code = 0.0;
  return scene;
}

TEST(MotionBlur, AddsTheBoxOfTheCamerasPathToTheEdgesSpread) {
  const SceneConfig scene = panningSquareOnScene();
  const World world(scene);
  // Frame 0: the pan's fastest, its acceleration nil.
  constexpr double kShutterFrames = 0.3;  // 10 ms of a 30 fps frame
  ImageRGB8 sharp, smeared;
  FrameTruth truth;
  world.render(0, sharp, truth);
  world.render(0, smeared, truth, 0.0, glm::dvec3(1.0), kShutterFrames);
  // The tag's left outer edge at the frame's middle row, where the
  // shutter opens and closes.
  const std::unique_ptr<CameraPath> path = makeCameraPath(scene);
  const glm::dvec3 edge_w(-0.5 * scene.rig.tag_size_m, 0.0, 0.0);
  const double opens_x = projectWorldPoints(scene.camera, path->poseAt(-0.5 * kShutterFrames), {edge_w})[0].x;
  const double closes_x = projectWorldPoints(scene.camera, path->poseAt(0.5 * kShutterFrames), {edge_w})[0].x;
  const double middle_x = projectWorldPoints(scene.camera, truth.pose, {edge_w})[0].x;
  const double path_px = std::abs(closes_x - opens_x);
  ASSERT_GT(path_px, 4.0) << "the pan must move the edge by several pixels";
  const int x0 = static_cast<int>(std::floor(middle_x));
  const int centre_y = static_cast<int>(scene.camera.cy_px);
  // The box's half and a margin either side, short of the next edges
  // (the white ring's outer edge 12.5 px out, the first data cell's 12.5
  // px in), themselves smeared by half the path.
  const int reach = static_cast<int>(std::ceil(0.5 * path_px)) + 4;
  ASSERT_LT(reach + 0.5 * path_px + 1.0, 12.5);
  const double sharp_variance = testing::edgeSpreadVariance(sharp, x0, reach, centre_y - 30, centre_y + 30);
  const double added = testing::edgeSpreadVariance(smeared, x0, reach, centre_y - 30, centre_y + 30) - sharp_variance;
  const double expected = path_px * path_px / 12.0;
  std::printf("pan over 10 ms: edge path %.2f px, spread variance +%.3f px^2 (box %.3f)\n", path_px, added, expected);
  // A midpoint rule of n instants gives the box's variance times
  // (1 - 1/n^2), n >= the path in pixels (2% short here); the black
  // border's 8-bit codes lose the faint tails, as for the lens: 10%.
  EXPECT_NEAR(added, expected, 0.1 * expected);
  // The smear is centred on the frame's pose: the edge's mean stays.
  EXPECT_NEAR(middle_x, 0.5 * (opens_x + closes_x), 0.05);
}

TEST(MotionBlur, AStillCameraRendersTheSameBytesWithTheShutterOpen) {
  SceneConfig scene = testing::smallScene();
  scene.camera_path.name = "static";
  const World world(scene);
  ImageRGB8 instant, exposed;
  FrameTruth truth;
  world.render(3, instant, truth);
  world.render(3, exposed, truth, 0.0, glm::dvec3(1.0), 0.3);
  EXPECT_EQ(instant.pixels, exposed.pixels);
}

TEST(CameraPath, PoseAtAFrameIsTheFramesPose) {
  SceneConfig scene = defaultScene();
  for (const std::string& name : cameraPathNames()) {
    scene.camera_path.name = name;
    const std::unique_ptr<CameraPath> path = makeCameraPath(scene);
    const PoseCamFromWorld at = path->poseAt(7.0), frame = path->pose(7);
    EXPECT_EQ(at.t_cam_from_world, frame.t_cam_from_world) << name;
  }
}

}  // namespace
}  // namespace probelight::sim
