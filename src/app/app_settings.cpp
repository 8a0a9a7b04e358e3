#include "app/app_settings.hpp"

#include <filesystem>

#include "capture/camera_format_choice.hpp"
#include "config/config_reader.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {

using config::ConfigReader;
using config::Range;

AppSettings loadAppSettings(const std::string& path) {
  AppSettings settings;
  ConfigReader file(path);

  ConfigReader maps = file.section("environment_maps");
  passes::EnvironmentMapSettings& stages = settings.maps.stages;
  stages.reflection_face_size = maps.readInt("face_size", stages.reflection_face_size, Range::closed(8, 1024));
  if ((stages.reflection_face_size & (stages.reflection_face_size - 1)) != 0)
    maps.fail("face_size", std::to_string(stages.reflection_face_size) + " is not a power of two");
  stages.prefilter_face_size =
      maps.readInt("prefilter_face_size", stages.prefilter_face_size, Range::closed(1, 1024));
  const int factor = stages.reflection_face_size / stages.prefilter_face_size;
  if (stages.reflection_face_size % stages.prefilter_face_size != 0 || factor > 8)
    maps.fail("prefilter_face_size", "must divide face_size (" + std::to_string(stages.reflection_face_size) +
                                         ") by a factor of 1 to 8");
  // Fields of the cube intermediate map the diffuse passes no longer use: a
  // clear word instead of "unknown field" for a file written for it.
  if (maps.has("intermediate_face_size"))
    maps.fail("intermediate_face_size",
              "no longer used: the diffuse passes now keep a latitude-longitude map; set intermediate_rows instead");
  if (maps.has("pole_direct_deg"))
    maps.fail("pole_direct_deg",
              "no longer used: the diffuse passes' latitude-longitude map has no pole to correct; remove the line");
  stages.intermediate_rows = maps.readInt("intermediate_rows", stages.intermediate_rows, Range::closed(4, 128));
  if (stages.intermediate_rows % 2 != 0)
    maps.fail("intermediate_rows", std::to_string(stages.intermediate_rows) + " is odd (the north pass needs an even count)");
  stages.diffuse_face_size = maps.readInt("diffuse_face_size", stages.diffuse_face_size, Range::closed(4, 256));
  stages.blur_half_taps = maps.readInt("half_taps", stages.blur_half_taps, Range::closed(1, 32));
  stages.normal_iterations = maps.readInt("normal_iterations", stages.normal_iterations, Range::closed(1, 16));
  // Powers of two: the passes divide sizes into one another (prefilter,
  // glossy levels), and GLES2 limits non-power-of-two textures.
  for (const auto& [field, size] : {std::pair{"prefilter_face_size", stages.prefilter_face_size},
                                    {"diffuse_face_size", stages.diffuse_face_size}})
    if ((size & (size - 1)) != 0) maps.fail(field, std::to_string(size) + " is not a power of two");
  const std::string transfer = maps.readString("camera_transfer", "srgb", {"srgb", "gamma", "linear"});
  stages.camera_transfer.curve = transfer == "gamma"    ? ibl::CameraTransfer::Curve::kGamma
                                 : transfer == "linear" ? ibl::CameraTransfer::Curve::kLinear
                                                        : ibl::CameraTransfer::Curve::kSrgb;
  stages.camera_transfer.gamma =
      maps.readDouble("camera_gamma", stages.camera_transfer.gamma, Range::openClosed(0.0, 5.0));
  stages.glossy_levels = maps.readInt("glossy_levels", stages.glossy_levels, Range::closed(0, 2));
  const std::string method = maps.readString("diffuse_method", "cosine", {"cosine", "sh9"});
  settings.maps.diffuse_method = method == "sh9" ? DiffuseMethod::kSH9 : DiffuseMethod::kCosinePasses;
  settings.maps.force_8bit = maps.readBool("force_8bit", settings.maps.force_8bit);
  settings.maps.merge_views = maps.readBool("merge_views", settings.maps.merge_views);
  maps.rejectUnknownFields();

  ConfigReader tracking = file.section("tracking");
  settings.tracking.quad_decimate =
      tracking.readDouble("quad_decimate", settings.tracking.quad_decimate, Range::closed(1.0, 8.0));
  settings.tracking.threads = tracking.readInt("threads", settings.tracking.threads, Range::closed(1, 16));
  if (settings.tracking.threads > probelight::tracking::maxDetectorThreads())
    tracking.fail("threads", std::to_string(settings.tracking.threads) +
                                 " needs libapriltag 3.4.3 or later; this build's " +
                                 probelight::tracking::aprilTagVersion() +
                                 " crashes at random with more than 1 (AprilRobotics/apriltag#339)");
  settings.tracking.quad_sigma = tracking.readDouble("quad_sigma", settings.tracking.quad_sigma, Range::closed(0.0, 5.0));
  settings.tracking.refine_edges = tracking.readBool("refine_edges", settings.tracking.refine_edges);
  settings.tracking.refine_corners = tracking.readBool("refine_corners", settings.tracking.refine_corners);
  settings.tracking.refinement_reuse_px =
      tracking.readDouble("refinement_reuse_px", settings.tracking.refinement_reuse_px, Range::closed(0.0, 10.0));
  settings.tracking.refinement_reuse_frames =
      tracking.readInt("refinement_reuse_frames", settings.tracking.refinement_reuse_frames, Range::closed(0, 100000));
  settings.tracking.track_in_window = tracking.readBool("track_in_window", settings.tracking.track_in_window);
  settings.tracking.full_frame_every_frames =
      tracking.readInt("full_frame_every_frames", settings.tracking.full_frame_every_frames, Range::closed(1, 100000));
  ConfigReader smoothing = tracking.section("smoothing");
  tracking::PoseSmoothingSettings& smooth = settings.tracking.smoothing;
  smooth.enabled = smoothing.readBool("enabled", smooth.enabled);
  smooth.static_cutoff_hz = smoothing.readDouble("static_cutoff_hz", smooth.static_cutoff_hz, Range::openClosed(0.0, 1000.0));
  smooth.max_lag_px = smoothing.readDouble("max_lag_px", smooth.max_lag_px, Range::openClosed(0.0, 100.0));
  smooth.speed_cutoff_hz = smoothing.readDouble("speed_cutoff_hz", smooth.speed_cutoff_hz, Range::openClosed(0.0, 1000.0));
  smooth.reset_jump_px = smoothing.readDouble("reset_jump_px", smooth.reset_jump_px, Range::openClosed(0.0, 10000.0));
  smoothing.rejectUnknownFields();
  tracking.rejectUnknownFields();

  ConfigReader object = file.section("object");
  settings.object.radius_m = object.readDouble("radius", settings.object.radius_m, Range::openClosed(0.0, 10.0));
  const glm::dvec3 position = object.readVec3(
      "position", glm::dvec3(settings.object.position_w, 0.0), Range::closed(-100.0, 100.0));
  if (position.z != 0.0) object.fail("position", "the object rests on the ground: give [x, y, 0]");
  settings.object.position_w = glm::dvec2(position);
  settings.object.albedo = object.readVec3("albedo", settings.object.albedo, Range::closed(0.0, 1.0));
  settings.object.k_specular = object.readDouble("k_specular", settings.object.k_specular, Range::closed(0.0, 10.0));
  settings.object.shininess = object.readDouble("shininess", settings.object.shininess, Range::closed(1.0, 4096.0));
  settings.object.k_reflect = object.readDouble("k_reflect", settings.object.k_reflect, Range::closed(0.0, 1.0));
  settings.object.glossiness = object.readDouble("glossiness", settings.object.glossiness, Range::closed(0.0, 1.0));
  settings.object.model_path = object.readString("model", settings.object.model_path);
  if (!settings.object.model_path.empty() && std::filesystem::path(settings.object.model_path).is_relative())
    settings.object.model_path =
        (std::filesystem::path(path).parent_path() / settings.object.model_path).lexically_normal().string();
  settings.object.yaw_deg = object.readDouble("yaw", settings.object.yaw_deg, Range::closed(-360.0, 360.0));
  settings.object.scale = object.readDouble("scale", settings.object.scale, Range::openClosed(0.0, 1000.0));
  settings.object.self_shadow = object.readBool("self_shadow", settings.object.self_shadow);
  object.rejectUnknownFields();

  ConfigReader recalibration = file.section("recalibration");
  settings.recalibration.good_frames_needed =
      recalibration.readInt("good_frames", settings.recalibration.good_frames_needed, Range::closed(1, 1000));
  settings.recalibration.max_frames =
      recalibration.readInt("max_frames", settings.recalibration.max_frames, Range::closed(1, 100000));
  if (settings.recalibration.max_frames < settings.recalibration.good_frames_needed)
    recalibration.fail("max_frames", "must be at least good_frames");
  recalibration.rejectUnknownFields();

  ConfigReader updates = file.section("map_updates");
  MapUpdateSettings& policy = settings.map_updates;
  policy.min_probe_radius_px =
      updates.readDouble("min_probe_radius_px", policy.min_probe_radius_px, Range::closed(1.0, 10000.0));
  policy.max_center_shift_px =
      updates.readDouble("max_center_shift_px", policy.max_center_shift_px, Range::closed(0.0, 10000.0));
  policy.max_radius_change_px =
      updates.readDouble("max_radius_change_px", policy.max_radius_change_px, Range::closed(0.0, 10000.0));
  policy.max_rotation_change_deg =
      updates.readDouble("max_rotation_change_deg", policy.max_rotation_change_deg, Range::closed(0.0, 180.0));
  policy.change_threshold_code =
      updates.readDouble("change_threshold_code", policy.change_threshold_code, Range::closed(0.0, 255.0));
  policy.max_age_frames = updates.readInt("max_age_frames", policy.max_age_frames, Range::atLeast(1));
  // 0 would never let a change in: the map would stay the first one forever.
  policy.smoothing_new_weight =
      updates.readDouble("smoothing_new_weight", policy.smoothing_new_weight, Range::openClosed(0.0, 1.0));
  updates.rejectUnknownFields();

  ConfigReader lights = file.section("lights");
  LightsConfig& light_settings = settings.lights;
  light_settings.dome.light_count = lights.readInt("count", light_settings.dome.light_count, Range::closed(1, 64));
  const std::string placement = lights.readString("placement", "clustered", {"clustered", "median_cut", "fixed"});
  light_settings.dome.placement = placement == "fixed"        ? ibl::DomePlacement::kFixedRegions
                                  : placement == "median_cut" ? ibl::DomePlacement::kMedianCut
                                                              : ibl::DomePlacement::kClustered;
  light_settings.fade_s = lights.readDouble("fade_s", light_settings.fade_s, Range::closed(0.0, 60.0));
  light_settings.shadows = lights.readBool("shadows", light_settings.shadows);
  light_settings.shadows_every_frame =
      lights.readString("shadow_updates", "on_change", {"on_change", "every_frame"}) == "every_frame";
  light_settings.shadow_map_size_px =
      lights.readInt("shadow_map_size", light_settings.shadow_map_size_px, Range::closed(16, 4096));
  light_settings.ground_texture_size_px =
      lights.readInt("ground_texture_size", light_settings.ground_texture_size_px, Range::closed(16, 4096));
  light_settings.max_shadow_reach_m =
      lights.readDouble("max_shadow_reach", light_settings.max_shadow_reach_m, Range::openClosed(0.0, 100.0));
  light_settings.refit_when_light_changes =
      lights.readBool("refit_when_light_changes", light_settings.refit_when_light_changes);
  light_settings.refit_change_fraction =
      lights.readDouble("refit_change_fraction", light_settings.refit_change_fraction, Range::openClosed(0.0, 10.0));
  light_settings.white_reference = lights.readBool("white_reference", light_settings.white_reference);
  light_settings.post_reference = lights.readBool("post_reference", light_settings.post_reference);
  light_settings.bracket_step_stops =
      lights.readDouble("bracket_step_stops", light_settings.bracket_step_stops, Range::closed(0.5, 8.0));
  light_settings.bracket_max_stops =
      lights.readDouble("bracket_max_stops", light_settings.bracket_max_stops, Range::closed(0.0, 20.0));
  lights.rejectUnknownFields();

  ConfigReader button = file.section("button");
  GpioButtonSettings& gpio = settings.button.gpio;
  gpio.chip = button.readString("chip", gpio.chip);
  gpio.line = button.readInt("line", gpio.line, Range::closed(0, 1023));
  gpio.debounce.debounce_ms = button.readDouble("debounce_ms", gpio.debounce.debounce_ms, Range::closed(0.0, 1000.0));
  gpio.debounce.long_press_ms =
      button.readDouble("long_press_ms", gpio.debounce.long_press_ms, Range::closed(100.0, 60000.0));
  settings.button.led.chip = gpio.chip;
  settings.button.led.line = button.readInt("led_line", settings.button.led.line, Range::closed(-1, 1023));
  settings.button.led.active_low = button.readBool("led_active_low", settings.button.led.active_low);
  if (settings.button.led.line >= 0 && settings.button.led.line == gpio.line)
    throw config::ConfigError(button.path() + ": field '" + button.fieldName("led_line") + "': the LED cannot share the button's line " +
                      std::to_string(gpio.line));
  button.rejectUnknownFields();

  ConfigReader camera_section = file.section("camera");
  settings.camera.id = camera_section.readString("id", settings.camera.id);
  settings.camera.pixel_format =
      camera_section.readString("pixel_format", settings.camera.pixel_format, cameraFormatConfigNames());
  settings.camera.lock_exposure = camera_section.readBool("lock_exposure", settings.camera.lock_exposure);
  settings.camera.exposure_settle_frames =
      camera_section.readInt("exposure_settle_frames", settings.camera.exposure_settle_frames, Range::closed(0, 10000));
  settings.camera.reconnect_max_interval_s = camera_section.readDouble(
      "reconnect_max_interval_s", settings.camera.reconnect_max_interval_s, Range::closed(0.5, 3600.0));
  camera_section.rejectUnknownFields();

  ConfigReader display = file.section("display");
  KmsDisplaySettings& kms = settings.display.kms;
  kms.device = display.readString("device", kms.device);
  kms.mode.connector = display.readString("connector", kms.mode.connector);
  kms.mode.width_px = display.readInt("width", kms.mode.width_px, Range::closed(0, 16384));
  kms.mode.height_px = display.readInt("height", kms.mode.height_px, Range::closed(0, 16384));
  kms.mode.refresh_hz = display.readDouble("refresh_hz", kms.mode.refresh_hz, Range::closed(0.0, 1000.0));
  if ((kms.mode.width_px == 0) != (kms.mode.height_px == 0)) display.fail("width", "width and height go together (both 0: the preferred mode)");
  display.rejectUnknownFields();

  ConfigReader state = file.section("state");
  settings.state.dir = state.readString("dir", settings.state.dir);
  state.rejectUnknownFields();

  ConfigReader refinement = file.section("probe_refinement");
  settings.probe_refinement.enabled = refinement.readBool("enabled", settings.probe_refinement.enabled);
  settings.probe_refinement.weight =
      refinement.readDouble("weight", settings.probe_refinement.weight, Range::openClosed(0.0, 1.0));
  refinement.rejectUnknownFields();

  ConfigReader camera_match = file.section("camera_match");
  settings.camera_match.response = camera_match.readBool("response", settings.camera_match.response);
  settings.camera_match.noise = camera_match.readBool("noise", settings.camera_match.noise);
  settings.camera_match.noise_smoothing_new_weight =
      camera_match.readDouble("noise_smoothing_new_weight", settings.camera_match.noise_smoothing_new_weight,
                              Range::openClosed(0.0, 1.0));
  settings.camera_match.blur = camera_match.readBool("blur", settings.camera_match.blur);
  settings.camera_match.blur_smoothing_new_weight =
      camera_match.readDouble("blur_smoothing_new_weight", settings.camera_match.blur_smoothing_new_weight,
                              Range::openClosed(0.0, 1.0));
  settings.camera_match.bloom = camera_match.readBool("bloom", settings.camera_match.bloom);
  settings.camera_match.bloom_sigma_deg =
      camera_match.readDouble("bloom_sigma_deg", settings.camera_match.bloom_sigma_deg, Range::openClosed(0.0, 10.0));
  settings.camera_match.motion_blur = camera_match.readBool("motion_blur", settings.camera_match.motion_blur);
  camera_match.rejectUnknownFields();

  ConfigReader lamp_section = file.section("virtual_lamp");
  VirtualLampConfig& lamp = settings.virtual_lamp;
  lamp.enabled = lamp_section.readBool("enabled", lamp.enabled);
  lamp.lamp.position_w = lamp_section.readVec3("position", lamp.lamp.position_w, Range::closed(-5.0, 5.0));
  lamp.lamp.colour = lamp_section.readVec3("colour", lamp.lamp.colour, Range::closed(0.0, 100.0));
  lamp.lamp.intensity = lamp_section.readDouble("intensity", lamp.lamp.intensity, Range::closed(0.0, 100.0));
  lamp.lamp.spot_direction_w =
      lamp_section.readVec3("spot_direction", lamp.lamp.spot_direction_w, Range::closed(-1.0, 1.0));
  lamp.lamp.spot_half_angle_deg =
      lamp_section.readDouble("spot_half_angle_deg", lamp.lamp.spot_half_angle_deg, Range::openClosed(0.0, 180.0));
  lamp.lamp.spot_softness_deg =
      lamp_section.readDouble("spot_softness_deg", lamp.lamp.spot_softness_deg, Range::closed(0.0, 90.0));
  // What the ranges cannot say (above the ground, a direction not zero).
  if (const std::optional<ibl::VirtualLampProblem> problem = ibl::virtualLampProblem(lamp.lamp))
    throw config::ConfigError(lamp_section.path() + ": field '" + lamp_section.fieldName(problem->field) +
                              "': " + problem->message);
  lamp_section.rejectUnknownFields();

  ConfigReader sim = file.section("sim");
  settings.sim.env = sim.readString("env", settings.sim.env);
  settings.sim.camera_path = sim.readString("camera_path", settings.sim.camera_path);
  settings.sim.noise_sigma = sim.readDouble("noise_sigma", settings.sim.noise_sigma, Range::closed(0.0, 64.0));
  settings.sim.lens_blur_sigma =
      sim.readDouble("lens_blur_sigma", settings.sim.lens_blur_sigma, Range::closed(0.0, 16.0));
  settings.sim.seed = sim.readInt("seed", settings.sim.seed, Range::atLeast(0));
  settings.sim.sun_azimuth_rate_deg_per_frame = sim.readDouble(
      "sun_azimuth_rate_deg_per_frame", settings.sim.sun_azimuth_rate_deg_per_frame, Range::closed(-90.0, 90.0));
  settings.sim.environment_rotation_deg = sim.readDouble("environment_rotation_deg", settings.sim.environment_rotation_deg,
                                                        Range::closed(-360.0, 360.0));
  settings.sim.lamp_on_frame = sim.readInt("lamp_on_frame", settings.sim.lamp_on_frame, Range::atLeast(-1));
  settings.sim.lamp_off_frame = sim.readInt("lamp_off_frame", settings.sim.lamp_off_frame, Range::atLeast(-1));
  settings.sim.ball_offset_m = sim.readVec3("ball_offset", settings.sim.ball_offset_m, Range::closed(-0.1, 0.1));
  // Every camera format but MJPEG, whose decoding is the libcamera source's.
  std::vector<std::string> sim_formats = {"rgb"};
  for (const CameraFormatInfo& format : cameraFormats())
    if (format.format != CameraFormat::kMjpeg) sim_formats.push_back(format.config_name);
  settings.sim.pixel_format = sim.readString("pixel_format", settings.sim.pixel_format, sim_formats);
  settings.sim.camera_lost_at_frame =
      sim.readInt("camera_lost_at_frame", settings.sim.camera_lost_at_frame, Range::atLeast(-1));
  settings.sim.camera_silent_at_frame =
      sim.readInt("camera_silent_at_frame", settings.sim.camera_silent_at_frame, Range::atLeast(-1));
  settings.sim.camera_silent_s = sim.readDouble("camera_silent_s", settings.sim.camera_silent_s, Range::closed(0.0, 60.0));
  settings.sim.camera_lost_restarts =
      sim.readInt("camera_lost_restarts", settings.sim.camera_lost_restarts, Range::closed(0, 1000));
  settings.sim.min_exposure_us =
      sim.readDouble("min_exposure_us", settings.sim.min_exposure_us, Range::closed(0.0, 1e6));
  settings.sim.min_exposure_reported = sim.readBool("min_exposure_reported", settings.sim.min_exposure_reported);
  settings.sim.exposure_control = sim.readBool("exposure_control", settings.sim.exposure_control);
  settings.sim.exposure_stops = sim.readDouble("exposure_stops", settings.sim.exposure_stops, Range::closed(-16.0, 16.0));
  settings.sim.response_shift_from_frame =
      sim.readInt("response_shift_from_frame", settings.sim.response_shift_from_frame, Range::atLeast(-1));
  settings.sim.response_shift_until_frame =
      sim.readInt("response_shift_until_frame", settings.sim.response_shift_until_frame, Range::atLeast(-1));
  settings.sim.exposure_shift_stops =
      sim.readDouble("exposure_shift_stops", settings.sim.exposure_shift_stops, Range::closed(-16.0, 16.0));
  settings.sim.white_balance_shift_red =
      sim.readDouble("white_balance_shift_red", settings.sim.white_balance_shift_red, Range::closed(0.125, 8.0));
  settings.sim.white_balance_shift_blue =
      sim.readDouble("white_balance_shift_blue", settings.sim.white_balance_shift_blue, Range::closed(0.125, 8.0));
  settings.sim.motion_blur = sim.readBool("motion_blur", settings.sim.motion_blur);
  settings.sim.lens_control = sim.readBool("lens_control", settings.sim.lens_control);
  settings.sim.camera_buffers = sim.readInt("camera_buffers", settings.sim.camera_buffers, Range::closed(2, 16));
  sim.rejectUnknownFields();

  ConfigReader output = file.section("output");
  settings.save_every = output.readInt("save_every", settings.save_every, Range::atLeast(0));
  settings.gpu_finish = output.readBool("gpu_finish", settings.gpu_finish);
  settings.resources_every_frames =
      output.readInt("resources_every_frames", settings.resources_every_frames, Range::atLeast(0));
  output.rejectUnknownFields();

  ConfigReader faults = file.section("faults");
  settings.faults.camera_loss_every_frames =
      faults.readInt("camera_loss_every_frames", settings.faults.camera_loss_every_frames, Range::atLeast(0));
  settings.faults.camera_loss_failed_restarts = faults.readInt(
      "camera_loss_failed_restarts", settings.faults.camera_loss_failed_restarts, Range::closed(0, 1000));
  faults.rejectUnknownFields();

  file.rejectUnknownFields();
  return settings;
}

}  // namespace probelight
