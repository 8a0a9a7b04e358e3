// Environment names, lat-long files and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "sim/camera_path.hpp"
#include "sim/environment.hpp"
#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

std::filesystem::path tempPath(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("probelight_sim_test_" + std::to_string(::getpid()) + "_" + name);
}

TEST(LatLong, MappingPutsZenithOnTopAndPlusXInTheMiddle) {
  glm::dvec2 up = latLongUvFromDirection({0, 0, 1});
  EXPECT_NEAR(up.y, 0.0, 1e-12);
  glm::dvec2 x = latLongUvFromDirection({1, 0, 0});
  EXPECT_NEAR(x.x, 0.5, 1e-12);
  EXPECT_NEAR(x.y, 0.5, 1e-12);
  // Turning right (toward -Y, viewer facing +X with +Z up) moves right in the image.
  EXPECT_NEAR(latLongUvFromDirection({0, -1, 0}).x, 0.75, 1e-12);
  EXPECT_NEAR(latLongUvFromDirection({0, 1, 0}).x, 0.25, 1e-12);
  for (glm::dvec3 d : {glm::dvec3{0.3, -0.2, 0.9}, {-0.7, 0.1, -0.2}, {-0.5, -0.5, 0.1}}) {
    d = glm::normalize(d);
    glm::dvec3 back = directionFromLatLongUv(latLongUvFromDirection(d));
    EXPECT_NEAR(glm::length(back - d), 0.0, 1e-12);
  }
}

// Writes a lat-long image whose texel (col, row) is (1 + col, 1 + row, 7) and
// checks texel centres read back through the direction mapping.
void checkRoundTrip(const std::string& extension, double relative_tolerance) {
  const int width = 64, height = 32;
  cv::Mat bgr(height, width, CV_32FC3);
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) bgr.at<cv::Vec3f>(row, col) = cv::Vec3f(7.0f, 1.0f + row, 1.0f + col);
  std::filesystem::path path = tempPath("roundtrip" + extension);
  ASSERT_TRUE(cv::imwrite(path.string(), bgr)) << path;
  auto environment = makeEnvironment(path.string());
  std::filesystem::remove(path);
  for (auto [col, row] : {std::pair{0, 0}, {31, 16}, {50, 5}, {63, 31}}) {
    glm::dvec3 dir = directionFromLatLongUv({(col + 0.5) / width, (row + 0.5) / height});
    glm::dvec3 rgb = environment->radiance(dir);
    EXPECT_NEAR(rgb.r, 1.0 + col, relative_tolerance * (1.0 + col)) << col << "," << row;
    EXPECT_NEAR(rgb.g, 1.0 + row, relative_tolerance * (1.0 + row)) << col << "," << row;
    EXPECT_NEAR(rgb.b, 7.0, relative_tolerance * 64.0) << col << "," << row;
  }
}

TEST(LatLong, HdrFileReadsBackTexelCentresInRgbOrder) {
  // RGBE keeps 8 mantissa bits under a shared exponent: relative error up to
  // 1/256 of the largest channel (<= 64 here) per channel.
  checkRoundTrip(".hdr", 1.0 / 128.0);
}

TEST(LatLong, ExrFileReadsBackTexelCentresInRgbOrder) {
  setenv("OPENCV_IO_ENABLE_OPENEXR", "1", 0);
  cv::Mat probe(2, 4, CV_32FC3, cv::Scalar(1, 1, 1));
  std::filesystem::path path = tempPath("probe.exr");
  bool can_write_exr = false;
  try {
    can_write_exr = cv::imwrite(path.string(), probe);
  } catch (const cv::Exception&) {
  }
  std::filesystem::remove(path);
  if (!can_write_exr) GTEST_SKIP() << "this OpenCV cannot write EXR";
  checkRoundTrip(".exr", 1e-6);  // float EXR is lossless
}

TEST(LatLong, RotationTurnsTheEnvironmentCounterClockwise) {
  SceneConfig scene = testing::smallScene();
  scene.environment = "coloured_wall";  // red wall toward +X
  scene.environment_rotation_deg = 90.0;
  World world(scene);
  glm::dvec3 toward_y = glm::normalize(glm::dvec3{0, 1, 0.3});
  glm::dvec3 toward_x = glm::normalize(glm::dvec3{1, 0, 0.3});
  auto unrotated = makeEnvironment("coloured_wall");
  EXPECT_NEAR(world.radiance(toward_y, 0).hdr.r / world.exposure(), unrotated->radiance(toward_x).r, 1e-9);
  EXPECT_GT(world.radiance(toward_y, 0).hdr.r, 2.0 * world.radiance(toward_y, 0).hdr.g);  // the wall is red
}

TEST(SceneErrors, MissingEnvironmentFileIsNamed) {
  SceneConfig scene = testing::smallScene();
  scene.environment = "/nonexistent/dir/studio_panorama.exr";
  try {
    World world(scene);
    FAIL() << "expected SceneError";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/studio_panorama.exr"), std::string::npos) << e.what();
  }
}

TEST(SceneErrors, UndecodableEnvironmentFileIsNamed) {
  std::filesystem::path path = tempPath("garbage.hdr");
  std::ofstream(path) << "this is not a radiance file\n";
  SceneConfig scene = testing::smallScene();
  scene.environment = path.string();
  try {
    World world(scene);
    FAIL() << "expected SceneError";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(SceneErrors, UnknownNamesAndBadValuesNameTheField) {
  auto message_for = [](SceneConfig scene) -> std::string {
    try {
      World world(scene);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  };
  SceneConfig scene = testing::smallScene();
  scene.environment = "moonlight";
  EXPECT_NE(message_for(scene).find("moonlight"), std::string::npos);
  scene = testing::smallScene();
  scene.camera_path.name = "spiral";
  EXPECT_NE(message_for(scene).find("camera_path.name"), std::string::npos);
  scene = testing::smallScene();
  scene.rig.tag_family = "tag99h1";
  EXPECT_NE(message_for(scene).find("rig.tag_family"), std::string::npos);
  scene = testing::smallScene();
  scene.rig.tag_id = 100000;
  EXPECT_NE(message_for(scene).find("rig.tag_id"), std::string::npos);
  scene = testing::smallScene();
  scene.rig.probe_reflectance = 0.0;
  EXPECT_NE(message_for(scene).find("rig.probe_reflectance"), std::string::npos);
}

TEST(Names, EveryListedEnvironmentAndPathBuilds) {
  for (const std::string& name : environmentNames()) EXPECT_EQ(makeEnvironment(name)->name(), name);
  for (const std::string& name : cameraPathNames()) {
    SceneConfig scene = testing::smallScene();
    scene.supersample_per_axis = 1;
    scene.camera_path.name = name;
    EXPECT_NO_THROW(World world(scene)) << name;
  }
}

}  // namespace
}  // namespace probelight::sim

namespace probelight::sim {
namespace {

// The two real HDR worlds in tests/data/env (see tests/data/LICENSES.md) are
// upright in our lat-long mapping: their light comes from above. Checked on
// the data, not assumed: the mean radiance of the upper hemisphere exceeds the
// lower one's, and the brightest direction (sun, stage lamps) is above the
// horizon. A vertically flipped mapping fails both.
TEST(RealHdrWorlds, AreUprightAndBrighterAbove) {
  for (const char* name : {"KernerEnvLatLong.exr", "StageEnvLatLong.exr"}) {
    const std::string path = std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/" + name;
    auto environment = makeEnvironment(path);
    double upper = 0.0, lower = 0.0, brightest = -1.0;
    glm::dvec3 brightest_direction{0.0};
    const int rows = 90, cols = 180;
    for (int row = 0; row < rows; ++row) {
      for (int col = 0; col < cols; ++col) {
        const glm::dvec3 dir = directionFromLatLongUv({(col + 0.5) / cols, (row + 0.5) / rows});
        const glm::dvec3 rgb = environment->radiance(dir);
        const double y = 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b;
        const double weight = std::sqrt(std::max(0.0, 1.0 - dir.z * dir.z));  // solid angle ~ sin(theta)
        (dir.z > 0 ? upper : lower) += y * weight;
        if (y > brightest) {
          brightest = y;
          brightest_direction = dir;
        }
      }
    }
    EXPECT_GT(upper, 1.5 * lower) << name;
    EXPECT_GT(brightest_direction.z, 0.1) << name;
    EXPECT_GT(brightest, 100.0) << name << ": HDR values survive loading (peaks are in the thousands)";
  }
}

}  // namespace
}  // namespace probelight::sim

namespace probelight::sim {
namespace {

// The sweep goes sweep_azimuth_deg either side of the start and back in
// 2 x sweep_seconds at 30 fps: at its turns the eye's azimuth about the
// point it looks at is the start -+ the sweep (the wobble's drift, 2 cm at
// 0.55 m seen from above at 25 deg, moves it by at most
// atan(0.02 / (0.55 cos 25 deg)) = 2.3 deg), and it comes back to where it began.
TEST(CameraPaths, TheHandHeldSweepTurnsAtItsEndsAndComesBack) {
  SceneConfig scene = defaultScene();
  scene.camera_path.name = "hand_held_sweep";
  scene.camera_path.distance_m = 0.55;
  scene.camera_path.elevation_deg = 25.0;
  const glm::dvec3 target(0.1, 0.05, 0.0);
  scene.camera_path.look_at_w = target;
  const std::unique_ptr<CameraPath> path = makeCameraPath(scene);
  const CameraPathConfig& config = scene.camera_path;
  const auto one_way = static_cast<std::uint64_t>(30.0 * config.sweep_seconds);
  auto eyeAzimuthDeg = [&](std::uint64_t frame) {
    const glm::dvec3 eye = path->pose(frame).cameraCenterWorld();
    return std::atan2(eye.y - target.y, eye.x - target.x) * 180.0 / std::numbers::pi;
  };
  const double start = config.azimuth_start_deg;
  EXPECT_NEAR(eyeAzimuthDeg(0), start - config.sweep_azimuth_deg, 2.3);
  EXPECT_NEAR(eyeAzimuthDeg(one_way), start + config.sweep_azimuth_deg, 2.3);
  EXPECT_NEAR(eyeAzimuthDeg(2 * one_way), eyeAzimuthDeg(0), 2.3);
  // Never a jump: at most the arc's fastest, pi/2 x 70 deg / 90 frames =
  // 1.2 deg a frame, plus the drift's.
  for (std::uint64_t frame = 1; frame <= 2 * one_way; ++frame)
    EXPECT_LT(std::abs(eyeAzimuthDeg(frame) - eyeAzimuthDeg(frame - 1)), 1.5) << frame;
}

}  // namespace
}  // namespace probelight::sim
