#include <gtest/gtest.h>

#include <string>

#include "app/app_settings.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"

namespace probelight {
namespace {

const std::string kBoardDir = std::string(PROBELIGHT_TEST_DATA_DIR) + "/../../board";

// board/probelight.yaml documents every setting with its default value: it
// must load, and say the same as the code's defaults.
TEST(AppSettings, BoardFileListsEveryFieldWithTheDefaults) {
  const AppSettings from_file = loadAppSettings(kBoardDir + "/probelight.yaml");
  const AppSettings defaults;
  EXPECT_EQ(from_file.maps.face_size, defaults.maps.face_size);
  EXPECT_EQ(from_file.maps.diffuse_face_size, defaults.maps.diffuse_face_size);
  EXPECT_DOUBLE_EQ(from_file.maps.blur_sigma_rad, defaults.maps.blur_sigma_rad);
  EXPECT_EQ(from_file.maps.blur_half_taps, defaults.maps.blur_half_taps);
  EXPECT_EQ(from_file.maps.normal_iterations, defaults.maps.normal_iterations);
  EXPECT_EQ(from_file.maps.force_8bit, defaults.maps.force_8bit);
  EXPECT_DOUBLE_EQ(from_file.tracking.quad_decimate, defaults.tracking.quad_decimate);
  EXPECT_EQ(from_file.tracking.threads, defaults.tracking.threads);
  EXPECT_DOUBLE_EQ(from_file.object.radius_m, defaults.object.radius_m);
  EXPECT_EQ(from_file.object.albedo, defaults.object.albedo);
  EXPECT_EQ(from_file.recalibration.good_frames_needed, defaults.recalibration.good_frames_needed);
  EXPECT_EQ(from_file.recalibration.max_frames, defaults.recalibration.max_frames);
  EXPECT_EQ(from_file.sim.env, defaults.sim.env);
  EXPECT_EQ(from_file.sim.camera_path, defaults.sim.camera_path);
  EXPECT_EQ(from_file.sim.lamp_on_frame, defaults.sim.lamp_on_frame);
  EXPECT_EQ(from_file.save_every, defaults.save_every);
  EXPECT_EQ(from_file.gpu_finish, defaults.gpu_finish);
}

TEST(AppSettings, BoardCameraAndRigTemplatesLoad) {
  const CameraIntrinsics camera = config::loadCameraFile(kBoardDir + "/camera.yaml");
  EXPECT_GT(camera.fx_px, 0.0);
  const RigGeometry rig = config::loadRigFile(kBoardDir + "/rig.yaml");
  EXPECT_GT(rig.probe_radius_m, 0.0);
}

TEST(AppSettings, PartialFileChangesOnlyWhatItLists) {
  const std::string path = ::testing::TempDir() + "/partial_probelight.yaml";
  FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fputs("environment_maps:\n  face_size: 128\nsim:\n  lamp_on_frame: 30\n", file);
  std::fclose(file);
  const AppSettings settings = loadAppSettings(path);
  EXPECT_EQ(settings.maps.face_size, 128);
  EXPECT_EQ(settings.sim.lamp_on_frame, 30);
  EXPECT_EQ(settings.maps.diffuse_face_size, AppSettings{}.maps.diffuse_face_size);
}

TEST(AppSettings, ObjectMustRestOnTheGround) {
  const std::string path = ::testing::TempDir() + "/floating_probelight.yaml";
  FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fputs("object:\n  position: [0, 0, 0.2]\n", file);
  std::fclose(file);
  try {
    loadAppSettings(path);
    FAIL() << "a floating object was accepted";
  } catch (const config::ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("object.position"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace probelight
