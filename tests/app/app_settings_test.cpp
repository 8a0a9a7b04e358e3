#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "app/app_settings.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {
namespace {

const std::string kBoardDir = std::string(PROBELIGHT_TEST_DATA_DIR) + "/../../board";

// board/probelight.yaml documents every setting with its default value: it
// must load, and say the same as the code's defaults.
TEST(AppSettings, BoardFileListsEveryFieldWithTheDefaults) {
  const AppSettings from_file = loadAppSettings(kBoardDir + "/probelight.yaml");
  const AppSettings defaults;
  EXPECT_EQ(from_file.maps.stages.reflection_face_size, defaults.maps.stages.reflection_face_size);
  EXPECT_EQ(from_file.maps.stages.prefilter_face_size, defaults.maps.stages.prefilter_face_size);
  EXPECT_EQ(from_file.maps.stages.intermediate_rows, defaults.maps.stages.intermediate_rows);
  EXPECT_EQ(from_file.maps.stages.diffuse_face_size, defaults.maps.stages.diffuse_face_size);
  EXPECT_EQ(from_file.maps.stages.blur_half_taps, defaults.maps.stages.blur_half_taps);
  EXPECT_EQ(from_file.maps.stages.normal_iterations, defaults.maps.stages.normal_iterations);
  EXPECT_EQ(from_file.maps.diffuse_method, defaults.maps.diffuse_method);
  EXPECT_EQ(from_file.maps.stages.camera_transfer.curve, defaults.maps.stages.camera_transfer.curve);
  EXPECT_DOUBLE_EQ(from_file.maps.stages.camera_transfer.gamma, defaults.maps.stages.camera_transfer.gamma);
  EXPECT_EQ(from_file.maps.stages.glossy_levels, defaults.maps.stages.glossy_levels);
  EXPECT_DOUBLE_EQ(from_file.object.glossiness, defaults.object.glossiness);
  EXPECT_EQ(from_file.object.model_path, defaults.object.model_path);
  EXPECT_DOUBLE_EQ(from_file.object.yaw_deg, defaults.object.yaw_deg);
  EXPECT_DOUBLE_EQ(from_file.object.scale, defaults.object.scale);
  EXPECT_EQ(from_file.object.self_shadow, defaults.object.self_shadow);
  EXPECT_EQ(from_file.maps.force_8bit, defaults.maps.force_8bit);
  EXPECT_DOUBLE_EQ(from_file.tracking.quad_decimate, defaults.tracking.quad_decimate);
  EXPECT_EQ(from_file.tracking.threads, defaults.tracking.threads);
  EXPECT_EQ(from_file.tracking.refine_edges, defaults.tracking.refine_edges);
  EXPECT_EQ(from_file.tracking.refine_corners, defaults.tracking.refine_corners);
  EXPECT_EQ(from_file.tracking.track_in_window, defaults.tracking.track_in_window);
  EXPECT_EQ(from_file.tracking.full_frame_every_frames, defaults.tracking.full_frame_every_frames);
  EXPECT_EQ(from_file.tracking.smoothing.enabled, defaults.tracking.smoothing.enabled);
  EXPECT_DOUBLE_EQ(from_file.tracking.smoothing.static_cutoff_hz, defaults.tracking.smoothing.static_cutoff_hz);
  EXPECT_DOUBLE_EQ(from_file.tracking.smoothing.max_lag_px, defaults.tracking.smoothing.max_lag_px);
  EXPECT_DOUBLE_EQ(from_file.tracking.smoothing.speed_cutoff_hz, defaults.tracking.smoothing.speed_cutoff_hz);
  EXPECT_DOUBLE_EQ(from_file.tracking.smoothing.reset_jump_px, defaults.tracking.smoothing.reset_jump_px);
  EXPECT_DOUBLE_EQ(from_file.object.radius_m, defaults.object.radius_m);
  EXPECT_EQ(from_file.object.albedo, defaults.object.albedo);
  EXPECT_EQ(from_file.recalibration.good_frames_needed, defaults.recalibration.good_frames_needed);
  EXPECT_EQ(from_file.recalibration.max_frames, defaults.recalibration.max_frames);
  EXPECT_EQ(from_file.sim.env, defaults.sim.env);
  EXPECT_EQ(from_file.sim.camera_path, defaults.sim.camera_path);
  EXPECT_EQ(from_file.sim.lamp_on_frame, defaults.sim.lamp_on_frame);
  EXPECT_DOUBLE_EQ(from_file.map_updates.min_probe_radius_px, defaults.map_updates.min_probe_radius_px);
  EXPECT_DOUBLE_EQ(from_file.map_updates.max_center_shift_px, defaults.map_updates.max_center_shift_px);
  EXPECT_DOUBLE_EQ(from_file.map_updates.max_radius_change_px, defaults.map_updates.max_radius_change_px);
  EXPECT_DOUBLE_EQ(from_file.map_updates.max_rotation_change_deg, defaults.map_updates.max_rotation_change_deg);
  EXPECT_DOUBLE_EQ(from_file.map_updates.change_threshold_code, defaults.map_updates.change_threshold_code);
  EXPECT_EQ(from_file.map_updates.max_age_frames, defaults.map_updates.max_age_frames);
  EXPECT_DOUBLE_EQ(from_file.map_updates.smoothing_new_weight, defaults.map_updates.smoothing_new_weight);
  EXPECT_EQ(from_file.lights.dome.light_count, defaults.lights.dome.light_count);
  EXPECT_EQ(from_file.lights.dome.placement, defaults.lights.dome.placement);
  EXPECT_DOUBLE_EQ(from_file.lights.fade_s, defaults.lights.fade_s);
  EXPECT_EQ(from_file.lights.shadows, defaults.lights.shadows);
  EXPECT_EQ(from_file.lights.shadows_every_frame, defaults.lights.shadows_every_frame);
  EXPECT_EQ(from_file.lights.shadow_map_size_px, defaults.lights.shadow_map_size_px);
  EXPECT_EQ(from_file.lights.ground_texture_size_px, defaults.lights.ground_texture_size_px);
  EXPECT_DOUBLE_EQ(from_file.lights.max_shadow_reach_m, defaults.lights.max_shadow_reach_m);
  EXPECT_EQ(from_file.lights.refit_when_light_changes, defaults.lights.refit_when_light_changes);
  EXPECT_DOUBLE_EQ(from_file.lights.refit_change_fraction, defaults.lights.refit_change_fraction);
  EXPECT_EQ(from_file.lights.white_reference, defaults.lights.white_reference);
  EXPECT_EQ(from_file.lights.post_reference, defaults.lights.post_reference);
  EXPECT_DOUBLE_EQ(from_file.lights.bracket_step_stops, defaults.lights.bracket_step_stops);
  EXPECT_DOUBLE_EQ(from_file.lights.bracket_max_stops, defaults.lights.bracket_max_stops);
  EXPECT_EQ(from_file.button.gpio.chip, defaults.button.gpio.chip);
  EXPECT_EQ(from_file.button.gpio.line, defaults.button.gpio.line);
  EXPECT_DOUBLE_EQ(from_file.button.gpio.debounce.debounce_ms, defaults.button.gpio.debounce.debounce_ms);
  EXPECT_DOUBLE_EQ(from_file.button.gpio.debounce.long_press_ms, defaults.button.gpio.debounce.long_press_ms);
  EXPECT_EQ(from_file.state.dir, defaults.state.dir);
  EXPECT_EQ(from_file.display.kms.device, defaults.display.kms.device);
  EXPECT_EQ(from_file.camera.id, defaults.camera.id);
  EXPECT_EQ(from_file.display.kms.mode.connector, defaults.display.kms.mode.connector);
  EXPECT_EQ(from_file.display.kms.mode.width_px, defaults.display.kms.mode.width_px);
  EXPECT_DOUBLE_EQ(from_file.display.kms.mode.refresh_hz, defaults.display.kms.mode.refresh_hz);
  EXPECT_EQ(from_file.probe_refinement.enabled, defaults.probe_refinement.enabled);
  EXPECT_DOUBLE_EQ(from_file.probe_refinement.weight, defaults.probe_refinement.weight);
  EXPECT_EQ(from_file.sim.ball_offset_m, defaults.sim.ball_offset_m);
  EXPECT_DOUBLE_EQ(from_file.sim.min_exposure_us, defaults.sim.min_exposure_us);
  EXPECT_EQ(from_file.sim.min_exposure_reported, defaults.sim.min_exposure_reported);
  EXPECT_EQ(from_file.sim.camera_buffers, defaults.sim.camera_buffers);
  EXPECT_EQ(from_file.sim.lens_control, defaults.sim.lens_control);
  EXPECT_EQ(from_file.save_every, defaults.save_every);
  EXPECT_EQ(from_file.gpu_finish, defaults.gpu_finish);
  EXPECT_EQ(from_file.resources_every_frames, defaults.resources_every_frames);
  EXPECT_EQ(from_file.faults.camera_loss_every_frames, defaults.faults.camera_loss_every_frames);
  EXPECT_EQ(from_file.faults.camera_loss_failed_restarts, defaults.faults.camera_loss_failed_restarts);
}

// The board profiles load, and say what differs from the defaults.
TEST(AppSettings, BoardProfilesLoad) {
  const AppSettings pi = loadAppSettings(kBoardDir + "/raspberry-pi/probelight.yaml");
  EXPECT_EQ(pi.state.dir, "/var/lib/probelight");
  EXPECT_EQ(pi.button.gpio.chip, "gpiochip0");
  EXPECT_EQ(pi.button.gpio.line, 17);
  EXPECT_EQ(pi.save_every, 0);
  const AppSettings desktop = loadAppSettings(kBoardDir + "/desktop-sim/probelight.yaml");
  EXPECT_EQ(desktop.state.dir, "state");
  EXPECT_EQ(desktop.sim.env, AppSettings{}.sim.env);
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
  EXPECT_EQ(settings.maps.stages.reflection_face_size, 128);
  EXPECT_EQ(settings.sim.lamp_on_frame, 30);
  EXPECT_EQ(settings.maps.stages.diffuse_face_size, AppSettings{}.maps.stages.diffuse_face_size);
}

// A model named relative to the config is found next to it, wherever the
// program runs from (the service runs in /); an absolute path stays.
TEST(AppSettings, ModelPathsAreRelativeToTheConfigFile) {
  const std::string dir = ::testing::TempDir() + "/model_config";
  std::filesystem::create_directories(dir);
  for (const auto& [given, expected] :
       {std::pair<std::string, std::string>{"models/statue.glb", dir + "/models/statue.glb"},
        {"/srv/models/statue.glb", "/srv/models/statue.glb"}}) {
    const std::string path = dir + "/probelight.yaml";
    FILE* file = std::fopen(path.c_str(), "w");
    ASSERT_NE(file, nullptr);
    std::fprintf(file, "object:\n  model: \"%s\"\n  yaw: 30\n  scale: 0.05\n", given.c_str());
    std::fclose(file);
    const AppSettings settings = loadAppSettings(path);
    EXPECT_EQ(std::filesystem::path(settings.object.model_path).lexically_normal(),
              std::filesystem::path(expected).lexically_normal());
    EXPECT_DOUBLE_EQ(settings.object.yaw_deg, 30.0);
    EXPECT_DOUBLE_EQ(settings.object.scale, 0.05);
  }
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

// A virtual lamp on or under the ground, a zero spot direction, a spot
// angle past a hemisphere or a negative intensity: refused, the field named.
TEST(AppSettings, VirtualLampFieldsAreChecked) {
  const std::string path = ::testing::TempDir() + "/lamp_probelight.yaml";
  for (const auto& [yaml, field] : {std::pair{"virtual_lamp:\n  position: [0, 0, 0]\n", "virtual_lamp.position"},
                                    std::pair{"virtual_lamp:\n  spot_direction: [0, 0, 0]\n", "virtual_lamp.spot_direction"},
                                    std::pair{"virtual_lamp:\n  spot_half_angle_deg: 200\n", "virtual_lamp.spot_half_angle_deg"},
                                    std::pair{"virtual_lamp:\n  intensity: -1\n", "virtual_lamp.intensity"},
                                    std::pair{"virtual_lamp:\n  colour: [1, .nan, 1]\n", "virtual_lamp.colour"}}) {
    FILE* file = std::fopen(path.c_str(), "w");
    ASSERT_NE(file, nullptr);
    std::fputs(yaml, file);
    std::fclose(file);
    try {
      loadAppSettings(path);
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const config::ConfigError& error) {
      EXPECT_NE(std::string(error.what()).find(field), std::string::npos) << error.what();
    }
  }
}

// A smoothing weight of 0 would keep the first map for ever: refused, with
// the file and the field named.
TEST(AppSettings, MapUpdateFieldsAreRangeChecked) {
  const std::string path = ::testing::TempDir() + "/map_updates_probelight.yaml";
  auto expectRejected = [&](const std::string& text, const std::string& field) {
    FILE* file = std::fopen(path.c_str(), "w");
    ASSERT_NE(file, nullptr);
    std::fputs(text.c_str(), file);
    std::fclose(file);
    try {
      loadAppSettings(path);
      FAIL() << text << " was accepted";
    } catch (const config::ConfigError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(field), std::string::npos) << message;
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  expectRejected("map_updates:\n  smoothing_new_weight: 0\n", "map_updates.smoothing_new_weight");
  // The cube intermediate's fields, gone with it: named, with what replaced them.
  expectRejected("environment_maps:\n  pole_direct_deg: 20\n", "environment_maps.pole_direct_deg");
  expectRejected("environment_maps:\n  intermediate_face_size: 32\n", "intermediate_rows");
  expectRejected("environment_maps:\n  intermediate_rows: 31\n", "environment_maps.intermediate_rows");
  expectRejected("map_updates:\n  max_age_frames: 0\n", "map_updates.max_age_frames");
  expectRejected("map_updates:\n  max_center_shift_px: -1\n", "map_updates.max_center_shift_px");
  expectRejected("map_updates:\n  change_treshold_code: 3\n", "change_treshold_code");
  // The keys the bracket and the post brought.
  expectRejected("sim:\n  camera_buffers: 1\n", "sim.camera_buffers");
  expectRejected("sim:\n  min_exposure_reported: maybe\n", "sim.min_exposure_reported");
  expectRejected("lights:\n  post_reference: 2\n", "lights.post_reference");
  // The soak's knobs.
  expectRejected("faults:\n  camera_loss_every_frames: -1\n", "faults.camera_loss_every_frames");
  expectRejected("faults:\n  camera_loss_failed_restarts: 1001\n", "faults.camera_loss_failed_restarts");
  expectRejected("faults:\n  camera_loss_every: 10\n", "camera_loss_every");
  expectRejected("output:\n  resources_every_frames: -5\n", "output.resources_every_frames");
  expectRejected("sim:\n  exposure_stops: 17\n", "sim.exposure_stops");
  // Worker threads libapriltag does not survive (its pool races before 3.4.3).
  const int too_many_threads = tracking::maxDetectorThreads() + 1;
  if (too_many_threads <= 16)
    expectRejected("tracking:\n  threads: " + std::to_string(too_many_threads) + "\n", "tracking.threads");
}

}  // namespace
}  // namespace probelight
