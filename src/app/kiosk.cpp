#include "app/kiosk.hpp"

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <thread>

#include <GLES2/gl2.h>
#include <opencv2/imgproc.hpp>

#include "app/app_settings.hpp"
#include "stages/bracket_merge.hpp"
#include "stages/light_transition.hpp"
#include "stages/lighting_state_machine.hpp"
#include "core/log_priority.hpp"
#include "stages/post_report.hpp"
#include "stages/map_update_policy.hpp"
#include "stages/run_report.hpp"
#include "app/reconnect_backoff.hpp"
#include "app/service_notify.hpp"
#include "app/shutdown_request.hpp"
#include "stages/stage_settings.hpp"
#include "stages/state_store.hpp"
#include "capture/image_frame_source.hpp"
#include "capture/libcamera_source.hpp"
#include "capture/sim_frame_source.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "core/apriltag_families.hpp"
#include "display/display.hpp"
#include "gles/capabilities.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/light_dome.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_outline.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "ibl/white_reference.hpp"
#include "input/button_source.hpp"
#include "input/status_led.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/object_compositor.hpp"
#include "sim/world.hpp"
#include "tracking/pose_smoother.hpp"
#include "tracking/probe_edge_fit.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// How often the run compares the GPU maps with the simulator's truth; the
// read-back is not part of the product's frame cost.
constexpr std::uint64_t kTruthCheckEveryFrames = 10;

double rotationErrorDeg(const glm::dmat3& estimated, const glm::dmat3& truth) {
  const glm::dmat3 difference = estimated * glm::transpose(truth);
  const double cosine = (difference[0][0] + difference[1][1] + difference[2][2] - 1.0) * 0.5;
  return std::acos(std::clamp(cosine, -1.0, 1.0)) * kRadToDeg;
}

// JSON has no NaN: a missing figure is null.
nlohmann::json finiteOrNull(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

void recordSeries(nlohmann::json& out, const std::string& name, const SampleSeries& series) {
  if (series.empty()) return;
  out[name] = {{"median", series.median()}, {"p95", series.percentile(95.0)}, {"max", series.max()},
               {"samples", series.count()}};
}

using ibl::luminance;

// Status text drawn over the frame with OpenCV's Hershey font, re-rendered
// only when the text changes.
class StatusOverlay {
 public:
  const std::vector<std::uint8_t>& render(const std::string& text, int width, int height) {
    if (text == text_ && width == width_ && height == height_) return rgba_;
    text_ = text;
    width_ = width;
    height_ = height;
    cv::Mat canvas(height, width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
    const double scale = std::max(0.4, width / 1280.0);
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    const int bar_height = size.height + baseline + 12;
    cv::rectangle(canvas, cv::Rect(0, height - bar_height, width, bar_height), cv::Scalar(0, 0, 0, 160), cv::FILLED);
    cv::putText(canvas, text, cv::Point(8, height - baseline - 6), cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(255, 255, 255, 255), 1, cv::LINE_AA);
    rgba_.assign(canvas.data, canvas.data + canvas.total() * 4);
    return rgba_;
  }

 private:
  std::string text_;
  int width_ = 0;
  int height_ = 0;
  std::vector<std::uint8_t> rgba_;
};

struct LoadedInputs {
  AppSettings settings;
  CameraIntrinsics camera;
  RigGeometry rig;
  bool camera_from_file = false;
  bool rig_from_file = false;
};

// Reads every file the run needs before anything starts, so that a bad one
// costs nothing but its one-line message.
LoadedInputs loadInputs(const RunOptions& options) {
  LoadedInputs inputs;
  if (!options.config_path.empty()) inputs.settings = loadAppSettings(options.config_path);
  if (!options.camera_path.empty()) {
    inputs.camera = config::loadCameraFile(options.camera_path);
    inputs.camera_from_file = true;
  }
  if (!options.rig_path.empty()) {
    inputs.rig = config::loadRigFile(options.rig_path);
    inputs.rig_from_file = true;
  }
  if (options.save_every) inputs.settings.save_every = *options.save_every;
  if (!options.sim_env.empty()) inputs.settings.sim.env = options.sim_env;
  if (!options.sim_path.empty()) inputs.settings.sim.camera_path = options.sim_path;
  return inputs;
}

// Errors against the simulator's truth for one frame.
// `unsmoothed_pose`: the tracker's own pose when smoothing replaced it in `track`.
void measureAgainstTruth(const FrameTruth& truth, const tracking::TagTrackResult& track,
                         const ibl::ProbeOutline* outline, const std::optional<ibl::MirrorBallView>& unsmoothed_view,
                         RunReport& report) {
  if (!track.found) return;
  if (unsmoothed_view) {
    report.recordAccuracy("pose_rotation_error_deg_unsmoothed",
                          rotationErrorDeg(unsmoothed_view->pose.R_cam_from_world, truth.pose.R_cam_from_world));
    const ibl::ProbeOutline raw_outline = ibl::computeProbeOutline(*unsmoothed_view);
    if (raw_outline.valid && truth.probe_radius_px > 0.0)
      report.recordAccuracy("probe_center_error_px_unsmoothed", glm::length(raw_outline.center_px - truth.probe_center_px));
  }
  report.recordAccuracy("pose_rotation_error_deg", rotationErrorDeg(track.pose.R_cam_from_world,
                                                                    truth.pose.R_cam_from_world));
  const double distance = glm::length(truth.pose.t_cam_from_world);
  report.recordAccuracy("pose_translation_error_pct",
                        100.0 * glm::length(track.pose.t_cam_from_world - truth.pose.t_cam_from_world) / distance);
  if (outline && outline->valid && truth.probe_radius_px > 0.0) {
    report.recordAccuracy("probe_center_error_px", glm::length(outline->center_px - truth.probe_center_px));
    report.recordAccuracy("probe_radius_error_px", std::abs(outline->radius_px - truth.probe_radius_px));
  }
}

// Compares the GPU's maps with the simulator's radiance and irradiance.
// `view`: the one the maps were made from. Returns the mean relative error of
// the diffuse map against the 8-bit-visible irradiance (NaN when not read).
double measureMapsAgainstTruth(const sim::World& world, std::uint64_t frame_index, const ibl::MirrorBallView& view,
                               const passes::EnvironmentMaps& maps, RunReport& report) {
  // Reflection map, over the directions the ball shows well: within 100
  // degrees of the direction back toward the camera (beyond that the view is
  // squeezed into the rim, and behind it is the blind spot). Only the sky
  // (z > 0) is compared: the environment there is distant, while the floor
  // below is so close to the ball that what its surface reflects differs from
  // the truth seen from its centre (parallax), which no environment map holds.
  std::string error;
  const std::optional<ibl::CubeMapRGB> reflection_read = maps.readReflection(error);
  const std::optional<ibl::CubeMapRGB> diffuse_read = maps.readDiffuse(error);
  if (!reflection_read || !diffuse_read) return std::nan("");
  const ibl::CubeMapRGB& reflection = *reflection_read;
  const glm::dvec3 to_camera = glm::normalize(view.pose.cameraCenterWorld() - view.center_w);
  const double rim_cosine = std::cos(100.0 / kRadToDeg);
  double abs_error_sum = 0.0;
  double truth_sum = 0.0;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < reflection.face_size; y += 2) {
      for (int x = 0; x < reflection.face_size; x += 2) {
        const glm::dvec3 direction = ibl::cubeTexelCenterDirection(face, x, y, reflection.face_size);
        if (direction.z <= 0.0 || glm::dot(direction, to_camera) < rim_cosine) continue;
        const glm::dvec3 truth = world.radiance(direction, frame_index).clipped;
        abs_error_sum += std::abs(luminance(glm::dvec3(reflection.texel(face, x, y))) - luminance(truth));
        truth_sum += luminance(truth);
      }
    }
  }
  if (truth_sum > 0.0) report.recordAccuracy("reflection_map_sky_rel_error", abs_error_sum / truth_sum);

  // Diffuse map: it stores a cosine-like average radiance, so irradiance is pi
  // times it. Compared on the up normal and the four horizontal ones.
  const ibl::CubeMapRGB& diffuse = *diffuse_read;
  const glm::dvec3 normals[] = {{0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  double clipped_error_sum = 0.0;
  int clipped_errors = 0;
  for (const glm::dvec3& normal : normals) {
    const sim::IrradianceTruth truth = world.irradiance(normal, frame_index);
    const double estimated = M_PI * luminance(glm::dvec3(diffuse.sampleBilinear(normal)));
    if (luminance(truth.clipped) > 0.0) {
      const double relative = std::abs(estimated - luminance(truth.clipped)) / luminance(truth.clipped);
      report.recordAccuracy("diffuse_irradiance_rel_error_vs_clipped", relative);
      clipped_error_sum += relative;
      ++clipped_errors;
    }
    if (luminance(truth.hdr) > 0.0)
      report.recordAccuracy("diffuse_irradiance_rel_error_vs_hdr",
                            std::abs(estimated - luminance(truth.hdr)) / luminance(truth.hdr));
  }
  return clipped_errors > 0 ? clipped_error_sum / clipped_errors : std::nan("");
}

std::string formatVector(const glm::dvec3& v) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "[" << v.x << ", " << v.y << ", " << v.z << "]";
  return out.str();
}

// One `probelight run`: owns every stage and seam, and walks each frame
// through them. Each method is one phase of the run, so a later stage (lights,
// shadows, HDR) has an obvious place to go.
class Kiosk {
 public:
  Kiosk(const RunOptions& options, std::ostream& log) : options_(options), log_(log) {}

  // The exit status: 0 ok, 1 runtime failure, 2 bad flags or configuration.
  int run() {
    if (const int status = setUp(); status != 0) return status;
    installShutdownHandlers();
    const auto loop_start = std::chrono::steady_clock::now();
    int status = frameLoop();
    // A bracket the run's end cut short (its frame limit, its stream, a
    // signal): the lights are fitted from what it has, and kept.
    if (status == 0 && bracket_) status = finishBracket(last_frame_number_);
    notifier_.stopping();
    const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
    source_->stop();
    if (status != 0) return status;
    return writeReport(elapsed_s);
  }

 private:
  // Reads every file, then opens source, display, GPU stages, tracker and
  // button, in that order, so that a bad file costs nothing but its message.
  int setUp() {
    try {
      inputs_ = loadInputs(options_);
    } catch (const config::ConfigError& error) {
      return fail(2, error.what());
    }
    if (const int status = makeSource(); status != 0) return status;
    if (const int status = openDisplayAndStages(); status != 0) return status;

    const AppSettings& settings = inputs_.settings;
    try {
      tracker_ = std::make_unique<tracking::TagTracker>(tagDetectorSettings(settings, inputs_.rig), inputs_.rig,
                                                        inputs_.camera);
      bracket_tracker_ = std::make_unique<tracking::TagTracker>(tagDetectorSettings(settings, inputs_.rig),
                                                                inputs_.rig, inputs_.camera);
      smoother_ = std::make_unique<tracking::PoseSmoother>(settings.tracking.smoothing, inputs_.camera,
                                                           tracking::smoothingReferencePoints(inputs_.rig));
    } catch (const std::invalid_argument& bad_setting) {
      return fail(2, std::string("tracking: ") + bad_setting.what());
    }

    std::string error;
    button_ = makeButtonSource(options_.button, options_.key_path, settings.button.gpio, error);
    if (!button_) return fail(2, error);
    if (!button_->start(error)) {
      // A board without the GPIO chip (or a desktop) still runs the kiosk:
      // without a button, said once.
      if (options_.button != "gpio") return fail(2, error);
      log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << error << "; running without a button\n";
      report_.extra["button_warning"] = error;
      button_ = std::make_unique<NoButton>();
    }
    status_led_ = std::make_unique<NoStatusLed>();
    if (settings.button.led.line >= 0) {
      auto led = std::make_unique<GpioStatusLed>(settings.button.led);
      if (led->start(error)) {
        status_led_ = std::move(led);
      } else {
        // A hint for the user, never a reason not to run: said once.
        log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << error << "; running without it\n";
        report_.extra["status_led_warning"] = error;
      }
    }
    if (!source_->start(error)) return fail(options_.source == "images" ? 2 : 1, error);

    material_ = objectMaterial(settings);
    object_center_w_ = glm::dvec3(settings.object.position_w, settings.object.radius_m);
    loadStoredLighting();
    machine_ = LightingStateMachine(settings.recalibration);
    map_policy_ = MapUpdatePolicy(settings.map_updates);
    reconnect_ = ReconnectBackoff(0.5, settings.camera.reconnect_max_interval_s);
    return 0;
  }

  int makeSource() {
    const AppSettings& settings = inputs_.settings;
    if (options_.source == "images") {
      source_ = std::make_unique<ImageFrameSource>(options_.images);
      return 0;
    }
    if (options_.source == "libcamera") {
      LibcameraSettings camera;
      camera.camera_id = settings.camera.id;
      camera.width_px = inputs_.camera.width_px;  // the calibrated size
      camera.height_px = inputs_.camera.height_px;
      camera.layout = settings.camera.pixel_format == "nv12" ? PixelLayout::kNv12 : PixelLayout::kI420;
      source_ = std::make_unique<LibcameraSource>(camera);
      return 0;
    }
    sim::SceneConfig scene = sim::defaultScene();
    scene.environment = settings.sim.env;
    scene.camera_path.name = settings.sim.camera_path;
    scene.noise_sigma_code = settings.sim.noise_sigma;
    scene.seed = static_cast<std::uint64_t>(settings.sim.seed);
    scene.lighting.sun_azimuth_rate_deg_per_frame = settings.sim.sun_azimuth_rate_deg_per_frame;
    scene.lighting.lamp_on_frame = settings.sim.lamp_on_frame;
    scene.lighting.lamp_off_frame = settings.sim.lamp_off_frame;
    if (inputs_.camera_from_file) scene.camera = inputs_.camera;
    if (inputs_.rig_from_file) scene.rig = inputs_.rig;
    // The simulated camera and rig are what the pipeline is told: a perfect
    // calibration, so that the errors measured are the pipeline's own...
    inputs_.camera = scene.camera;
    inputs_.rig = scene.rig;
    // ...unless sim.ball_offset says the real ball is elsewhere.
    scene.rig.probe_center_w += settings.sim.ball_offset_m;
    try {
      world_ = std::make_shared<const sim::World>(scene);
    } catch (const sim::SceneError& error) {
      return fail(2, error.what());
    }
    SimCameraOptions camera_options;
    camera_options.layout = settings.sim.pixel_format == "yuv420" ? PixelLayout::kI420
                            : settings.sim.pixel_format == "nv12" ? PixelLayout::kNv12
                                                                  : PixelLayout::kRgb8;
    camera_options.lost_at_frame = settings.sim.camera_lost_at_frame;
    camera_options.failed_restarts = settings.sim.camera_lost_restarts;
    camera_options.min_exposure_us = settings.sim.min_exposure_us;
    camera_options.min_exposure_reported = settings.sim.min_exposure_reported;
    source_ = std::make_unique<SimFrameSource>(world_, frameLimit(), settings.sim.camera_buffers, camera_options);
    return 0;
  }

  int openDisplayAndStages() {
    const AppSettings& settings = inputs_.settings;
    const CameraIntrinsics& camera = inputs_.camera;
    std::string error;
    display_ = makeDisplay(options_.display, options_.out_dir, settings.save_every, settings.display.kms, error);
    if (!display_ || !display_->open(camera.width_px, camera.height_px, error)) return fail(1, error);
    capabilities_ = gles::probeCapabilities();
    if (settings.maps.force_8bit) capabilities_ = capabilities_.withoutExtensions();
    if (!options_.quiet) log_ << "probelight: " << display_->describe() << ": " << capabilities_.summary() << "\n";

    if (!frame_texture_.init(capabilities_, error) ||
        !maps_.init(capabilities_, environmentMapSettings(settings), error) ||
        !compositor_.init(capabilities_, passes::ObjectCompositorSettings{}, maps_.storage(), error) ||
        (settings.lights.shadows && !ground_shadow_.init(capabilities_, groundShadowSettings(settings), error)))
      return fail(1, "GPU set-up failed: " + error);
    light_transition_ = LightTransition(settings.lights.fade_s);
    return 0;
  }

  int frameLoop() {
    int consecutive_timeouts = 0;
    while (frameLimit() == 0 || frames_done_ < frameLimit()) {
      if (const int signal_number = shutdownSignal(); signal_number != 0) {
        log_ << logPrefix(LogPriority::kInfo) << "probelight: " << (signal_number == SIGTERM ? "SIGTERM" : "SIGINT")
             << ": stopping after " << frames_done_ << " frames\n";
        return 0;
      }
      pollButton();
      status_led_->set(ledLitAt(ledPatternFor(machine_.state() == AppState::kRecalibrating, reconnect_.lost()),
                                monotonicNowS()));
      if (reconnect_.lost()) {
        if (const int status = whileCameraLost(); status != 0) return status;
        continue;
      }
      FrameLease lease;
      const FrameWait wait = source_->waitFrame(std::chrono::milliseconds(2000), lease);
      if (wait == FrameWait::kTimeout) {
        // A camera that stops delivering: keep the last picture, say so, and
        // after a long silence treat it as gone (re-open it).
        log_ << logPrefix(LogPriority::kWarning) << "probelight: no frame from " << source_->name() << " for 2 s\n";
        if (++consecutive_timeouts >= kTimeoutsBeforeReconnect && canReconnect()) {
          consecutive_timeouts = 0;
          cameraLost("no frame for " + std::to_string(2 * kTimeoutsBeforeReconnect) + " s");
        } else if (consecutive_timeouts >= 15) {
          log_ << logPrefix(LogPriority::kError) << "probelight: giving up: " << source_->name() << " delivered nothing for 30 s\n";
          return 0;
        }
        continue;
      }
      if (wait == FrameWait::kEndOfStream) return 0;
      if (wait == FrameWait::kError) {
        if (canReconnect()) {
          cameraLost(source_->lastError());
          continue;
        }
        log_ << logPrefix(LogPriority::kError) << "probelight: " << source_->name() << ": " << source_->lastError() << "\n";
        return 0;
      }
      consecutive_timeouts = 0;
      ++frames_since_camera_start_;
      recordExposure(lease->metadata);
      if (const int status = processFrame(*lease, frames_done_++); status != 0) return status;
    }
    return 0;
  }

  // Cameras come back; a folder of images that failed does not.
  bool canReconnect() const { return options_.source != "images"; }

  double monotonicNowS() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }

  void cameraLost(const std::string& why) {
    report_.count("camera_losses");
    last_camera_problem_ = why;
    log_ << logPrefix(LogPriority::kError) << "probelight: " << source_->name() << ": " << why
         << "; keeping the last frame and reconnecting\n";
    source_->stop();
    exposure_locked_ = false;  // a new stream starts with AE running
    if (bracket_) report_.count("brackets_cut_by_camera_loss");  // whileCameraLost finishes it
    settling_.reset();      // a new stream starts at its own exposure
    early_ladder_.reset();  // ... and asks for a ladder afresh
    reconnect_.onLost(monotonicNowS());
  }

  // The last frame stays on screen with a message (and the watchdog keeps
  // being fed: the service is healthy, the camera is not) until a reconnect
  // attempt, when due, succeeds.
  int whileCameraLost() {
    // A bracket the loss cut short: the lights are fitted from what it has.
    if (bracket_)
      if (const int failed = finishBracket(last_frame_number_); failed != 0) return failed;
    const double now_s = monotonicNowS();
    if (reconnect_.due(now_s)) {
      std::string error;
      if (source_->start(error)) {
        report_.count("camera_reconnects");
        log_ << logPrefix(LogPriority::kInfo) << "probelight: " << source_->name() << " is back after "
             << reconnect_.failedAttempts() + 1 << " attempt(s), " << std::fixed << std::setprecision(1)
             << now_s - reconnect_.lostSinceS() << " s\n";
        reconnect_.onReconnected();
        frames_since_camera_start_ = 0;
        return 0;
      }
      report_.count("camera_reconnect_failures");
      last_camera_problem_ = error;
      reconnect_.onAttemptFailed(now_s);
      log_ << logPrefix(LogPriority::kWarning) << "probelight: reconnect failed: " << error << "; next attempt in "
           << std::fixed << std::setprecision(1) << reconnect_.nextAttemptS() - now_s << " s\n";
    }
    const double wait_s = std::max(0.0, reconnect_.nextAttemptS() - monotonicNowS());
    const std::string status = "Camera lost: reconnecting" +
                               (wait_s > 0.95 ? " in " + std::to_string(static_cast<int>(wait_s + 0.5)) + " s" : "");
    if (!frame_texture_.empty()) {
      // Not logged: the loss and each attempt are, the countdown is not.
      if (const int failed = renderAndPresent(last_track_, status, last_frame_number_, false); failed != 0) return failed;
    } else {
      notifier_.frameShown();  // nothing to show yet; the service itself is alive
    }
    // A few redraws a second are plenty for a still picture.
    std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(1000.0 * std::min(0.2, wait_s)) + 1));
    return 0;
  }

  // Exposure time and gain of every frame (the ball's brightness follows
  // them), and AE/AWB frozen while the lights are fitted.
  void recordExposure(const FrameMetadata& metadata) {
    if (metadata.exposure_us > 0.0) exposure_us_.add(metadata.exposure_us);
    if (metadata.analogue_gain > 0.0) analogue_gain_.add(metadata.analogue_gain);
    last_exposure_us_ = metadata.exposure_us;
    last_analogue_gain_ = metadata.analogue_gain;
  }

  void syncExposureLock() {
    const CameraConfig& config = inputs_.settings.camera;
    const bool want = config.lock_exposure && machine_.state() == AppState::kRecalibrating &&
                      frames_since_camera_start_ > static_cast<std::uint64_t>(config.exposure_settle_frames);
    if (want == exposure_locked_) return;
    if (!source_->lockExposure(want)) return;  // no such controls: nothing to say
    exposure_locked_ = want;
    report_.count(want ? "exposure_locks" : "exposure_unlocks");
  }

  void pollButton() {
    for (const ButtonEvent& event : button_->poll()) {
      if (event.kind == ButtonEvent::Kind::kLongPress) {
        // Back to the lighting stored at start-up (a fit that went wrong,
        // someone standing in front of the ball, is undone).
        if (stored_lighting_ && machine_.state() == AppState::kRunning && !bracket_) {
          showStoredLighting(frame_time_s_);
          report_.count("button_long_presses_restored");
          if (!options_.quiet) log_ << "probelight: button: long press: back to the stored lighting\n";
        } else {
          report_.count("button_long_presses_ignored");
          if (!options_.quiet)
            log_ << "probelight: button: long press ignored ("
                 << (stored_lighting_ ? "recalibrating" : "no stored lighting") << ")\n";
        }
        continue;
      }
      // A bracket still being taken is part of the recalibration before it.
      const bool was_running = machine_.state() == AppState::kRunning && !bracket_;
      if (was_running) machine_.onButtonPress();
      // The lights are fitted from a map made now, not a smoothed old one.
      if (was_running) map_policy_.requestFreshMap();
      report_.count(was_running ? "button_presses_accepted" : "button_presses_ignored");
      if (!options_.quiet)
        log_ << "probelight: button: " << (was_running ? "recalibrating lights" : "already recalibrating, ignored")
             << "\n";
    }
  }

  int processFrame(const FrameBuffer& frame, std::uint64_t frame_number) {
    const CameraIntrinsics& camera = inputs_.camera;
    const RigGeometry& rig = inputs_.rig;
    if (frame.width_px != camera.width_px || frame.height_px != camera.height_px) {
      // The calibration belongs to another resolution: using it would put the
      // object and the ball in the wrong place. Skip the frame, keep the state.
      report_.count("frames_wrong_size");
      log_ << "probelight: " << frame.metadata.origin << ": frame is " << frame.width_px << "x" << frame.height_px
           << " but the camera calibration is " << camera.width_px << "x" << camera.height_px << "; frame skipped\n";
      return 0;
    }
    // While an exposure bracket is taken, frames are its, not the picture's;
    // after it, frames still in flight at its exposures are not shown either.
    if (bracket_) return bracketFrame(frame, frame_number);
    if (early_ladder_ && rungArrivedEarly(frame)) {
      // The camera is quicker than the lead assumed: this frame is darker
      // than the fit's should be. Called off; the fit asks again.
      cancelEarlyLadder("bracket_early_ladders_too_early");
      bracket_lead_frames_ = 0;
    }
    if (settling_ && !exposureSettled(frame))
      return showKeptFrame(frame_number, "Recalibrating lights: exposure returning");
    std::string error;
    {
      StageTimer timer(report_, "upload");
      if (!frame_texture_.upload(frame, error)) return fail(1, frame.metadata.origin + ": " + error);
      gpuDone();
    }

    frame_time_s_ = static_cast<double>(frame.metadata.timestamp_ns) * 1e-9;
    tracking::TagTrackResult track;
    {
      StageTimer timer(report_, "detect_pose");
      // The Y' plane of a camera frame in place, or the luma the source made.
      const LumaView luma = frame.luma();
      track = tracker_->track(luma.data, luma.width, luma.height, luma.stride);
    }
    // Everything downstream (ball crop, maps, object) uses the smoothed pose.
    std::optional<ibl::MirrorBallView> unsmoothed_view;
    if (track.found && inputs_.settings.tracking.smoothing.enabled) {
      unsmoothed_view = ibl::MirrorBallView{camera, track.pose, rig.probe_center_w + probe_center_offset_w_,
                                            rig.probe_radius_m * probe_radius_scale_};
      track.pose = smoother_->update(track.pose, static_cast<double>(frame.metadata.timestamp_ns) * 1e-9);
    }

    // Stages 2-3: the maps, rebuilt only from a frame that shows the whole
    // ball, with a steady camera, and an image that says something new
    // (map_update_policy.hpp); otherwise the last good maps stay.
    // The rig's ball, as corrected by probe_refinement (nothing when it is off).
    const glm::dvec3 probe_center_w = rig.probe_center_w + probe_center_offset_w_;
    const double probe_radius_m = rig.probe_radius_m * probe_radius_scale_;
    const ibl::MirrorBallView view{camera, track.pose, probe_center_w, probe_radius_m};
    ibl::ProbeOutline outline;
    std::string status;
    tag_status_frames_[tracking::toString(track.status_code)] += 1;
    if (!track.found) {
      report_.count("frames_without_tag");
      status = (track.status_code == tracking::TagTrackStatus::kNoTag ? "No tag in view: " : "Tag not usable: ") +
               track.status;
      last_tag_problem_ = {{"frame", frame_number},
                           {"status", tracking::toString(track.status_code)},
                           {"message", track.status}};
    } else {
      outline = ibl::computeProbeOutline(view);
      refineProbe(view, outline, frame.luma());
    }
    MapFrameInput policy_input;
    policy_input.tag_found = track.found;
    policy_input.outline = outline;
    policy_input.rotation_cam_from_world = track.pose.R_cam_from_world;
    policy_input.luma = frame.luma();
    const MapUpdateDecision decision = map_policy_.decide(policy_input);
    recordDecision(decision);
    if (decision.skip == MapSkipReason::kBallNotInView)
      status = "Mirror ball not fully in view: lighting kept";
    else if (decision.skip == MapSkipReason::kBallTooSmall)
      status = "Mirror ball too small in the image: lighting kept";
    else if (decision.skip == MapSkipReason::kBallSaturated)
      status = "Mirror ball image all white (overexposed?): lighting kept";
    else if (decision.skip == MapSkipReason::kBallDark)
      status = "Mirror ball image all black (covered?): lighting kept";
    if (decision.update) {
      if (const int failed = updateMaps(view, rig.probe_reflectance, decision.new_weight); failed != 0) return failed;
      if (const int failed = rescaleClippedLights(frame_number); failed != 0) return failed;
      maps_view_ = view;
      if (const int failed = checkLightChange(frame_number); failed != 0) return failed;
    } else {
      report_.recordStageSkip("probe_to_cube", toString(decision.skip));
      report_.recordStageSkip(diffuseStageName(), toString(decision.skip));
    }

    // The state machine counts frames whose ball the maps hold: updated, or
    // skipped because the image matched the maps already.
    const bool maps_current = decision.update || decision.skip == MapSkipReason::kImageUnchanged;
    const FrameOutcome outcome = machine_.onFrame(maps_current);
    if (outcome == FrameOutcome::kNothing) leadTheLadder(frame, frame_number, track.found ? &outline : nullptr);
    switch (outcome) {
      case FrameOutcome::kFitLights:
        // With a bracket to take, the fit waits for its frames.
        if (track.found && startBracket(frame, frame_number, view, outline)) break;
        if (early_ladder_) cancelEarlyLadder("bracket_early_ladders_unused");
        if (const int failed = fitLights(frame_number, fitInputsOf(frame, track.found ? &view : nullptr)); failed != 0)
          return failed;
        break;
      case FrameOutcome::kCalibrationFailed:
        if (early_ladder_) cancelEarlyLadder("bracket_early_ladders_unused");
        report_.count("calibrations_failed");
        log_ << logPrefix(LogPriority::kWarning) << "probelight: frame " << frame_number << ": recalibration gave up (ball not seen in "
             << machine_.policy().max_frames << " frames); previous lighting kept\n";
        break;
      case FrameOutcome::kNothing:
        break;
    }
    syncExposureLock();
    if (machine_.state() == AppState::kRecalibrating) {
      status = "Recalibrating lights (" + std::to_string(machine_.goodFramesSoFar()) + "/" +
               std::to_string(machine_.policy().good_frames_needed) + ")" + (status.empty() ? "" : ": " + status);
      report_.count("frames_recalibrating");
    }

    if (const int failed = updateShadows(); failed != 0) return failed;
    if (const int failed = renderAndPresent(track, status, frame_number); failed != 0) return failed;
    last_track_ = track;
    last_frame_number_ = frame_number;

    if (frame.metadata.truth) {
      // How far the ball really moved since the previous frame: separates
      // the camera's motion from the pose noise in center_shift_px.
      const FrameTruth& truth = *frame.metadata.truth;
      if (truth.probe_radius_px > 0.0) {
        if (previous_truth_center_px_)
          truth_center_shift_px_.add(glm::length(truth.probe_center_px - *previous_truth_center_px_));
        previous_truth_center_px_ = truth.probe_center_px;
      } else {
        previous_truth_center_px_.reset();
      }
      measureAgainstTruth(*frame.metadata.truth, track, track.found ? &outline : nullptr, unsmoothed_view, report_);
      // Whatever the maps hold now, updated this frame or kept, against the
      // truth now: a map kept too long (a lamp switched on) shows here.
      if (world_ && have_maps_ && maps_view_ && frame_number % kTruthCheckEveryFrames == 0) {
        const double diffuse_error =
            measureMapsAgainstTruth(*world_, frame.metadata.sequence, *maps_view_, maps_, report_);
        truth_checks_.push_back({{"frame", frame_number},
                                 {"diffuse_irradiance_rel_error_vs_clipped", finiteOrNull(diffuse_error)},
                                 {"frames_since_map_update", map_policy_.framesSinceUpdate()}});
      }
    }
    return 0;
  }

  int updateMaps(const ibl::MirrorBallView& view, double probe_reflectance, float new_weight) {
    std::string error;
    {
      StageTimer timer(report_, "probe_to_cube");
      if (!maps_.updateReflection(frame_texture_, view, probe_reflectance, error)) return fail(1, error);
      gpuDone();
    }
    // Temporal smoothing in both methods: diffuse = w * new + (1 - w) * previous.
    if (inputs_.settings.maps.diffuse_method == DiffuseMethod::kSH9) {
      StageTimer timer(report_, diffuseStageName());
      std::vector<float> validity;
      const std::optional<ibl::CubeMapRGB> reflection = maps_.readReflection(error, &validity);
      if (!reflection) return fail(1, error);
      if (!maps_.updateDiffuseFromSH9(ibl::projectToSH9(*reflection, &validity), error, new_weight))
        return fail(1, error);
      gpuDone();
    } else {
      StageTimer timer(report_, diffuseStageName());
      if (!maps_.updateDiffuse(error, new_weight)) return fail(1, error);
      gpuDone();
    }
    // Glossy levels only when the object's material sits between them (a
    // mirror or a matte object never reads them).
    if (ibl::needsGlossy(material_)) {
      StageTimer timer(report_, "glossy");
      if (!maps_.updateGlossy(error)) return fail(1, error);
      gpuDone();
    }
    have_maps_ = true;
    return 0;
  }

  void recordDecision(const MapUpdateDecision& decision) {
    if (decision.update)
      ++map_update_causes_[toString(decision.cause)];
    else
      ++map_skip_reasons_[toString(decision.skip)];
    if (decision.center_shift_px) center_shift_px_.add(*decision.center_shift_px);
    if (decision.radius_change_px) radius_change_px_.add(*decision.radius_change_px);
    if (decision.rotation_change_deg) rotation_change_deg_.add(*decision.rotation_change_deg);
    if (decision.image_change_code) image_change_code_.add(*decision.image_change_code);
  }

  nlohmann::json mapUpdatesJson() const {
    nlohmann::json out;
    long long updated = 0;
    long long skipped = 0;
    for (const auto& [cause, n] : map_update_causes_) updated += n;
    for (const auto& [reason, n] : map_skip_reasons_) skipped += n;
    out["updated"] = updated;
    out["update_causes"] = map_update_causes_;
    out["skipped"] = skipped;
    out["skip_reasons"] = map_skip_reasons_;
    out["smoothing_new_weight"] = map_policy_.settings().smoothing_new_weight;
    // What the policy measured between consecutive frames (and against the
    // maps' reference), to see its thresholds' margins on a real run.
    nlohmann::json measured = nlohmann::json::object();
    recordSeries(measured, "center_shift_px", center_shift_px_);
    recordSeries(measured, "radius_change_px", radius_change_px_);
    recordSeries(measured, "rotation_change_deg", rotation_change_deg_);
    recordSeries(measured, "image_change_code", image_change_code_);
    recordSeries(measured, "truth_center_shift_px", truth_center_shift_px_);  // simulator only
    out["measured"] = measured;
    if (!truth_checks_.empty()) out["truth_checks"] = truth_checks_;
    return out;
  }

  // A recalibration has seen enough good frames: fit the lights from the
  // current diffuse map.
  // The object's clipped lights, each at `scale` of what was measured.
  void setClippedLights(const std::vector<double>& scale) {
    lighting_.clipped_direction_w = {};
    lighting_.clipped_diffuse_rgb = {};
    for (std::size_t k = 0; k < clipped_lights_.size() && k < lighting_.clipped_direction_w.size(); ++k) {
      lighting_.clipped_direction_w[k] = glm::vec3(clipped_lights_[k].direction_w);
      lighting_.clipped_diffuse_rgb[k] =
          glm::vec3(scale[k] * clipped_lights_[k].irradiance_rgb / 3.14159265358979323846);
    }
  }

  // Exposure time times gain of the newest frame (1 when the source cannot
  // say): camera-linear values scale with it.
  static double exposureProductOf(double exposure_us, double analogue_gain) {
    return exposure_us > 0.0 ? exposure_us * (analogue_gain > 0.0 ? analogue_gain : 1.0) : 1.0;
  }
  double exposureProduct() const { return exposureProductOf(last_exposure_us_, last_analogue_gain_); }

  // After each map update: the frame-rate maps are 8-bit, and the clipped
  // lights carry what they clip. Each light is scaled by the share of its
  // texels that still clip now over the share that did at the fit (a sun
  // gone behind a cloud, a lamp switched off: 0), and by the exposure now
  // over the exposure then (AE runs again after a fit, and the maps are in
  // the camera's linear units). One read-back of the reflection map per
  // map update, none when there are no clipped lights.
  int rescaleClippedLights(std::uint64_t frame_number) {
    if (clipped_lights_.empty()) return 0;
    std::vector<double> scale(clipped_lights_.size(), 1.0);
    {
      StageTimer timer(report_, "clipped_rescale");
      std::string error;
      const std::optional<ibl::CubeMapRGB> live = maps_.readReflection(error);
      if (!live) return fail(1, error);
      const double exposure_ratio = exposureProduct() / clipped_exposure_at_fit_;
      for (std::size_t k = 0; k < clipped_lights_.size(); ++k) {
        const double at_fit = clipped_share_at_fit_[k];
        const double share = at_fit > 0.0 ? std::min(1.0, ibl::stillClippedShare(clipped_lights_[k], *live, clipLevel()) / at_fit)
                                          : 1.0;  // nothing of it clipped in the map: it cannot be followed
        scale[k] = share * exposure_ratio;
      }
    }
    setClippedLights(scale);
    report_.count("clipped_rescales");
    report_.extra["clipped_lights_now"] = {{"frame", frame_number}, {"scale", scale}};
    return 0;
  }

  // What a fit has beyond the 8-bit maps: the fit frame's ball (null when
  // the tag was not found in it) and pixels, for the white border and the
  // clipped pixels; and an HDR map when a bracket was merged.
  // `exposure`: the 8-bit map's frame's (0: the source cannot say), the
  // unit of the camera-linear values.
  struct FitInputs {
    const ibl::MirrorBallView* view = nullptr;
    ibl::RgbPixelReader read;
    std::optional<ibl::CubeMapRGB> hdr;
    FrameSource::ManualExposure exposure{0.0, 0.0};
    bool exposure_locked = false;
  };
  FitInputs fitInputsOf(const FrameBuffer& frame, const ibl::MirrorBallView* view) const {
    FitInputs inputs;
    inputs.view = view;
    inputs.read = [&frame](int x, int y) { return frame.rgbAt(x, y); };
    inputs.exposure = {frame.metadata.exposure_us, frame.metadata.analogue_gain};
    inputs.exposure_locked = exposure_locked_;
    return inputs;
  }

  int fitLights(std::uint64_t frame_number, const FitInputs& inputs) {
    std::string error;
    std::vector<float> validity;
    const std::optional<ibl::CubeMapRGB> reflection = maps_.readReflection(error, &validity);
    if (!reflection) return fail(1, error);
    const LightsConfig& config = inputs_.settings.lights;
    std::vector<ibl::DomeLight> dome;
    ibl::DominantLight light;
    std::vector<ibl::ClippedLight> clipped_lights;
    {
      StageTimer timer(report_, "fit_lights");
      const ibl::CubeMapRGB* fit_map = &*reflection;
      double clip_level = 1.0 / inputs_.rig.probe_reflectance;
      std::optional<ibl::CubeMapRGB> corrected;
      if (inputs.hdr && inputs.view) {
        // A bracket measured the light: the clipped lights are what it holds
        // beyond the 8-bit map where that clipped.
        fit_map = &*inputs.hdr;
        clip_level = std::numeric_limits<double>::infinity();
        const ibl::HdrMergeSettings merge;
        const std::vector<std::uint8_t> mask =
            ibl::clippedTexelMask(*inputs.view, inputs.read, merge.clip_code, reflection->face_size);
        clipped_lights = ibl::clippedLights(*inputs.hdr, *reflection, &validity, clipLevel(), &mask);
        nlohmann::json lights = nlohmann::json::array();
        for (const ibl::ClippedLight& l : clipped_lights)
          lights.push_back({{"direction", {l.direction_w.x, l.direction_w.y, l.direction_w.z}},
                            {"irradiance_rgb", {l.irradiance_rgb.r, l.irradiance_rgb.g, l.irradiance_rgb.b}}});
        report_.extra["hdr"]["clipped_lights"] = lights;
      } else if (config.white_reference && inputs.view) {
        corrected = *reflection;
        if (whiteReference(inputs.read, *inputs.view, validity, *corrected, clipped_lights)) {
          fit_map = &*corrected;
          clip_level = std::numeric_limits<double>::infinity();  // nothing in it is clipped any more
        }
      }
      dome = ibl::fitLightDome(*fit_map, &validity, config.dome);
      light = ibl::findDominantLight(*fit_map, &validity, dome, clip_level, config.dome);
    }
    // The clipped lights follow the frame-rate maps from now on
    // (rescaleClippedLights): how much of each still clips in them, against
    // how much did in the map they were found beside.
    clipped_lights_ = std::move(clipped_lights);
    clipped_share_at_fit_.clear();
    for (const ibl::ClippedLight& light : clipped_lights_)
      clipped_share_at_fit_.push_back(ibl::stillClippedShare(light, *reflection, clipLevel()));
    clipped_exposure_at_fit_ = exposureProductOf(inputs.exposure.exposure_us, inputs.exposure.analogue_gain);
    setClippedLights(std::vector<double>(clipped_lights_.size(), 1.0));
    light_transition_.retarget(dome, frame_time_s_);
    // What checkLightChange compares with later: the same estimate, from the
    // same map.
    if (const std::optional<ibl::CubeMapRGB> diffuse = maps_.readDiffuse(error))
      lights_fitted_e_up_ = glm::dvec3(diffuse->sampleBilinear({0.0, 0.0, 1.0})) * 3.14159265358979323846;
    lighting_.highlight_direction_w = glm::vec3(light.direction_w);
    lighting_.highlight_rgb = glm::vec3(light.rgb);
    report_.count("calibrations_completed");
    // The ball's brightness in the fit follows these (0: the source cannot say).
    exposure_at_last_fit_ = {{"frame", frame_number},
                             {"exposure_us", inputs.exposure.exposure_us},
                             {"analogue_gain", inputs.exposure.analogue_gain},
                             {"locked", inputs.exposure_locked}};
    if (!inputs_.settings.state.dir.empty()) {
      // Kept for the next start; a failed write leaves the old file whole.
      std::string save_error;
      StoredLighting stored{dome, light, ibl::toString(config.dome.placement), clipped_lights_, clipped_share_at_fit_,
                            clipped_exposure_at_fit_};
      if (saveLighting(inputs_.settings.state.dir, stored, save_error))
        report_.count("state_saves");
      else
        log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: lighting not saved: " << save_error << "\n";
    }
    nlohmann::json lights = nlohmann::json::array();
    for (const ibl::DomeLight& l : dome)
      lights.push_back({{"direction", {l.direction_w.x, l.direction_w.y, l.direction_w.z}},
                        {"rgb", {l.rgb.r, l.rgb.g, l.rgb.b}},
                        {"spread_deg", glm::degrees(l.spread_rad)}});
    report_.extra["lights"] = {{"frame", frame_number},
                               {"placement", ibl::toString(config.dome.placement)},
                               {"lights", lights},
                               {"dominant_light",
                                {{"direction", {light.direction_w.x, light.direction_w.y, light.direction_w.z}},
                                 {"rgb", {light.rgb.r, light.rgb.g, light.rgb.b}},
                                 {"from_clipped_region", light.from_clipped_region}}}};
    if (!options_.quiet)
      log_ << "probelight: frame " << frame_number << ": lights recalibrated (" << dome.size() << ", "
           << ibl::toString(config.dome.placement) << "), dominant light toward " << formatVector(light.direction_w)
           << " rgb " << formatVector(light.rgb) << "\n";
    return 0;
  }

  // Texels at or above this clipped in the camera (the merge's clip code,
  // through the ball's reflectance).
  double clipLevel() const {
    return ibl::clippedMapLevel(ibl::HdrMergeSettings{inputs_.settings.maps.stages.camera_transfer},
                                inputs_.rig.probe_reflectance);
  }

  // The frame as 8-bit R'G'B' (decoded from Y'CbCr where it is YUV).
  static ImageRGB8 frameRgb(const FrameBuffer& frame) {
    if (frame.layout == PixelLayout::kRgb8) return frame.rgb;
    ImageRGB8 rgb;
    rgb.resize(frame.width_px, frame.height_px);
    for (int y = 0; y < frame.height_px; ++y)
      for (int x = 0; x < frame.width_px; ++x) {
        const glm::u8vec3 p = frame.rgbAt(x, y);
        std::uint8_t* out = rgb.row(y) + 3 * x;
        out[0] = p.r;
        out[1] = p.g;
        out[2] = p.b;
      }
    return rgb;
  }

  // lights.bracket_*: at a fit whose frame shows the ball clipped, shorter
  // exposures are taken, bracket_step_stops apart down to bracket_max_stops
  // (or the sensor's shortest exposure), while the ball still clips, and
  // merged with the frame into an HDR map (app/bracket_merge.hpp). The whole
  // ladder is asked for at once: the camera takes it one rung a frame, so
  // its latency is paid once, and the bracket ends at the first frame whose
  // ball no longer clips (the rungs after it are dropped or not looked at).
  // Bracket frames are not shown: the last frame stays, with a status line.
  // The rungs of a bracket: their EVs from the exposure they were planned
  // from, and the exposures asked for.
  struct ExposureLadder {
    std::vector<double> ev;                            // in stops from the base
    bool at_shortest = false;                          // its last rung is the sensor's shortest exposure
    std::vector<FrameSource::ManualExposure> exposures;
  };
  struct PendingBracket {
    ImageRGB8 reference;
    ibl::MirrorBallView view;
    ibl::ProbeOutline outline;
    FrameSource::ManualExposure base;  // the reference frame's exposure
    bool exposure_locked = false;      // ... and whether AE was locked for it
    ExposureLadder ladder;             // the rungs asked for, in stops from base
    int frames_waited = 0;             // since the request, or since the last frame kept
    std::vector<BracketCandidate> frames;
    std::uint64_t started_frame = 0;
    double started_s = 0.0;
    double own_s = 0.0;  // probelight's own work on the bracket's frames (the rest of the wall time is the camera's)
    int lead_frames = 0;  // the ladder was asked for this many frames before the fit frame
    int latency_frames = -1;  // from the request to its first rung (-1: none came)
  };
  // A requested exposure shows in a frame's metadata within a few frames
  // (libcamera queues a handful of requests ahead, and sensors apply
  // exposure changes two frames late); past this the bracket ends with what
  // it has.
  static constexpr int kBracketMaxWaitFrames = 8;
  // A frame counts as a rung within this many stops of it (sensors round
  // exposure time to whole lines).
  static constexpr double kBracketEvMatchStops = 0.25;
  // A bracket frame is kept when it is at least this much shorter than the
  // last one kept: it shows something the others clipped. (A frame caught
  // between rungs, where a sensor applies gain a frame before exposure time,
  // is kept too: its metadata says the exposure it had.)
  static constexpr double kBracketNewFrameStops = 2.0 * kBracketEvMatchStops;
  // Once the ladder's frames have begun they come one a frame: this many
  // frames with none shorter is a sensor that went no shorter than it said.
  static constexpr int kBracketClampedAfterFrames = 3;

  // Shorter by `ev` stops: the gain comes down to 1 first (any sensor takes
  // it, and it adds noise), then the exposure time, which sensors bound
  // below.
  static FrameSource::ManualExposure exposureAt(const FrameSource::ManualExposure& base, double ev) {
    const double gain = std::min(base.analogue_gain, 1.0);
    return {base.exposure_us * base.analogue_gain / gain * std::exp2(ev), gain};
  }

  // The rungs -step, -2 step, ... down to -max_stops, the ones below the
  // sensor's shortest exposure (where the source knows it) replaced by that
  // one exposure, and that one left out when it is hardly shorter than the
  // rung before it.
  ExposureLadder planLadder(const FrameSource::ManualExposure& base) const {
    const LightsConfig& config = inputs_.settings.lights;
    const std::optional<double> shortest_us = source_->shortestExposureUs();
    ExposureLadder ladder;
    for (double ev = -config.bracket_step_stops; ev >= -config.bracket_max_stops - 1e-9; ev -= config.bracket_step_stops) {
      FrameSource::ManualExposure exposure = exposureAt(base, ev);
      if (shortest_us && exposure.exposure_us < *shortest_us) {
        exposure.exposure_us = *shortest_us;
        const double shortest_ev =
            std::log2(exposure.exposure_us * exposure.analogue_gain / (base.exposure_us * base.analogue_gain));
        const double previous_ev = ladder.ev.empty() ? 0.0 : ladder.ev.back();
        if (shortest_ev <= previous_ev - kBracketNewFrameStops) {
          ladder.ev.push_back(shortest_ev);
          ladder.exposures.push_back(exposure);
        }
        ladder.at_shortest = true;
        break;
      }
      ladder.ev.push_back(ev);
      ladder.exposures.push_back(exposure);
    }
    return ladder;
  }

  // A frame's exposure as its metadata says (gain 1 where it does not say).
  static FrameSource::ManualExposure exposureOf(const FrameBuffer& frame) {
    return {frame.metadata.exposure_us, frame.metadata.analogue_gain > 0.0 ? frame.metadata.analogue_gain : 1.0};
  }

  // A recalibration whose ball clips asks for its ladder a few frames
  // before the fit frame (bracket_lead_frames_: the camera's latency less
  // one, learnt from the last bracket; 2 to begin with, as libcamera queues
  // requests ahead and sensors apply exposure two frames late), so that the
  // latency passes while the recalibration still counts its good frames at
  // the normal exposure and the rungs follow the fit frame at once.
  struct EarlyLadder {
    FrameSource::ManualExposure base;
    ExposureLadder ladder;
    std::uint64_t requested_frame = 0;
  };
  static constexpr int kBracketMaxLeadFrames = 6;

  void leadTheLadder(const FrameBuffer& frame, std::uint64_t frame_number, const ibl::ProbeOutline* outline) {
    const LightsConfig& config = inputs_.settings.lights;
    const int needed = machine_.policy().good_frames_needed;
    const int lead = std::min(bracket_lead_frames_, needed - 1);
    if (early_ladder_) {
      // The count started over (the ball was lost): not this time.
      if (machine_.state() != AppState::kRecalibrating || machine_.goodFramesSoFar() < needed - lead)
        cancelEarlyLadder("bracket_early_ladders_unused");
      return;
    }
    if (lead <= 0 || machine_.state() != AppState::kRecalibrating || machine_.goodFramesSoFar() != needed - lead ||
        !outline || !outline->valid || !(config.bracket_max_stops > 0.0) || !(frame.metadata.exposure_us > 0.0))
      return;
    const ibl::HdrMergeSettings merge{inputs_.settings.maps.stages.camera_transfer};
    if (ballPixelCodes(frameRgb(frame), *outline, merge).clipped == 0) return;
    EarlyLadder early{exposureOf(frame), {}, frame_number};
    early.ladder = planLadder(early.base);
    if (early.ladder.exposures.empty() || !source_->setExposureLadder(early.ladder.exposures)) return;  // the fit will say why
    early_ladder_ = std::move(early);
    report_.count("bracket_early_ladders");
  }

  bool rungArrivedEarly(const FrameBuffer& frame) const {
    const double ev = stopsFrom(frame, early_ladder_->base);
    return std::isfinite(ev) && ev < -kBracketEvMatchStops;
  }

  void cancelEarlyLadder(const char* counter) {
    source_->setExposureLadder({});
    settling_ = Settling{early_ladder_->base, 0};
    early_ladder_.reset();
    report_.count(counter);
  }

  bool startBracket(const FrameBuffer& frame, std::uint64_t frame_number, const ibl::MirrorBallView& view,
                    const ibl::ProbeOutline& outline) {
    const LightsConfig& config = inputs_.settings.lights;
    if (!(config.bracket_max_stops > 0.0) || !outline.valid) return false;
    if (!(frame.metadata.exposure_us > 0.0)) {
      report_.count("brackets_without_exposure_metadata");  // the EV of a frame could not be told
      return false;
    }
    const ibl::HdrMergeSettings merge{inputs_.settings.maps.stages.camera_transfer};
    PendingBracket bracket;
    bracket.reference = frameRgb(frame);
    bracket.view = view;
    bracket.outline = outline;
    bracket.exposure_locked = exposure_locked_;
    bracket.started_frame = frame_number;
    bracket.started_s = monotonicNowS();
    if (ballPixelCodes(bracket.reference, outline, merge).clipped == 0) {
      report_.count("brackets_not_needed");  // nothing clipped: the 8-bit map holds all the light
      return false;
    }
    bracket.base = exposureOf(frame);
    if (early_ladder_) {
      // Asked for a few frames ago: its rungs are on their way. Their EVs
      // from this frame's exposure (the same, with AE locked).
      const double shift = std::log2(early_ladder_->base.exposure_us * early_ladder_->base.analogue_gain /
                                     (bracket.base.exposure_us * bracket.base.analogue_gain));
      bracket.ladder = early_ladder_->ladder;
      for (double& ev : bracket.ladder.ev) ev += shift;
      bracket.lead_frames = static_cast<int>(frame_number - early_ladder_->requested_frame);
      early_ladder_.reset();
      report_.count("brackets_started");
      bracket_ = std::move(bracket);
      return true;
    }
    bracket.ladder = planLadder(bracket.base);
    if (bracket.ladder.exposures.empty()) {
      report_.count("brackets_at_shortest_exposure");  // the frame was already as short as the sensor goes
      return false;
    }
    if (!source_->setExposureLadder(bracket.ladder.exposures)) {
      report_.count("brackets_unsupported");
      return false;
    }
    report_.count("brackets_started");
    bracket_ = std::move(bracket);
    return true;
  }

  // A frame of (or just after) a bracket: not shown; the last frame stays,
  // with `status`. Every frame is accounted for in every stage: these skip
  // them all.
  int showKeptFrame(std::uint64_t frame_number, const std::string& status) {
    report_.count("frames_in_bracket");
    for (const char* stage : {"upload", "detect_pose", "probe_to_cube"}) report_.recordStageSkip(stage, "exposure_bracket");
    report_.recordStageSkip(diffuseStageName(), "exposure_bracket");
    ++map_skip_reasons_["exposure_bracket"];
    tag_status_frames_["exposure_bracket"] += 1;  // not looked for
    // The display's frame already holds the kept frame with this status
    // (nothing was drawn since): it is shown again, not drawn again.
    if (kept_frame_status_ == status) {
      report_.recordStageSkip("render", "kept_frame_unchanged");
      return presentFrame(status, frame_number, false);
    }
    if (const int failed = renderAndPresent(last_track_, status, frame_number, false); failed != 0) return failed;
    kept_frame_status_ = status;
    return 0;
  }

  // Stops of a frame's exposure from `base` (NaN when it does not say).
  static double stopsFrom(const FrameBuffer& frame, const FrameSource::ManualExposure& base) {
    if (!(frame.metadata.exposure_us > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    const double gain = frame.metadata.analogue_gain > 0.0 ? frame.metadata.analogue_gain : 1.0;
    return std::log2(frame.metadata.exposure_us * gain / (base.exposure_us * base.analogue_gain));
  }

  // After a bracket: true once a frame is back at the exposure from before
  // it (or after kBracketMaxWaitFrames, when the camera's AE has moved on).
  bool exposureSettled(const FrameBuffer& frame) {
    const double ev = stopsFrom(frame, settling_->base);
    if (!std::isfinite(ev) || std::abs(ev) <= kBracketEvMatchStops || ++settling_->frames_waited > kBracketMaxWaitFrames) {
      settling_.reset();
      return true;
    }
    return false;
  }

  int bracketFrame(const FrameBuffer& frame, std::uint64_t frame_number) {
    PendingBracket& bracket = *bracket_;
    const double entered_s = monotonicNowS();
    const double ev = stopsFrom(frame, bracket.base);
    const double last_ev = bracket.frames.empty() ? 0.0 : bracket.frames.back().ev;
    bool done = false;
    if (std::isfinite(ev) && ev <= last_ev - kBracketNewFrameStops) {
      // The camera's latency, learnt from its first rung: later brackets ask
      // for their ladder that many frames (less one) before the fit.
      if (bracket.frames.empty()) {
        bracket.latency_frames = static_cast<int>(frame_number - bracket.started_frame) + bracket.lead_frames;
        bracket_lead_frames_ = std::clamp(bracket.latency_frames - 1, 0, kBracketMaxLeadFrames);
      }
      BracketCandidate candidate{"camera frame " + std::to_string(frame_number), ev, frameRgb(frame)};
      const ibl::HdrMergeSettings merge{inputs_.settings.maps.stages.camera_transfer};
      const bool still_clips = ballPixelCodes(candidate.rgb, bracket.outline, merge).clipped > 0;
      bracket.frames.push_back(std::move(candidate));
      bracket.frames_waited = 0;
      report_.count("bracket_frames");
      const bool ladder_done = ev <= bracket.ladder.ev.back() + kBracketEvMatchStops;
      // The sensor's shortest exposure and the ball still clips: asking for
      // less would give the same again.
      if (still_clips && ladder_done && bracket.ladder.at_shortest) report_.count("bracket_exposures_clamped");
      done = !still_clips || ladder_done;
    } else if (!bracket.frames.empty()) {
      if (++bracket.frames_waited >= kBracketClampedAfterFrames) {
        report_.count("bracket_exposures_clamped");  // a limit the source did not tell
        done = true;
      }
    } else if (++bracket.frames_waited > kBracketMaxWaitFrames) {
      report_.count("bracket_exposures_not_delivered");
      log_ << logPrefix(LogPriority::kWarning) << "probelight: frame " << frame_number << ": the camera did not deliver EV "
           << std::fixed << std::setprecision(1) << bracket.ladder.ev.front() << " in " << kBracketMaxWaitFrames
           << " frames; the bracket ends with no frame\n";
      done = true;
    }
    // One status for the whole bracket, so that the kept frame is drawn once.
    if (const int failed = showKeptFrame(frame_number, "Recalibrating lights: exposure bracket"); failed != 0)
      return failed;
    bracket.own_s += monotonicNowS() - entered_s;
    return done ? finishBracket(frame_number) : 0;
  }

  // Merges what the bracket took (nothing usable: the fit goes on with the
  // white border) and fits the lights from it.
  int finishBracket(std::uint64_t frame_number) {
    PendingBracket bracket = std::move(*bracket_);
    bracket_.reset();
    source_->setExposureLadder({});
    settling_ = Settling{bracket.base, 0};
    const ibl::HdrMergeSettings merge{inputs_.settings.maps.stages.camera_transfer};
    // The camera took them in order: a frame too dark to show the tag was
    // taken right after the one before it.
    const BracketSetup setup{bracket.view, bracket.outline, inputs_.rig,
                             tagDetectorSettings(inputs_.settings, inputs_.rig), merge,
                             maps_.reflection().face_size, true, bracket_tracker_.get()};
    BracketMergeResult merged;
    const double merge_started_s = monotonicNowS();
    {
      StageTimer timer(report_, "bracket_merge");
      merged = mergeBracketProbe(bracket.reference, std::move(bracket.frames), setup,
                                 [&](const BracketCandidate& candidate, const std::string& why) {
                                   log_ << logPrefix(LogPriority::kWarning) << "probelight: bracket: " << candidate.label
                                        << " (EV " << std::fixed << std::setprecision(1) << candidate.ev
                                        << ") left out: " << why << "\n";
                                 });
    }
    report_.count(merged.hdr_cube ? "brackets_merged" : "brackets_unusable");
    report_.extra["hdr"] = {{"method", merged.hdr_cube ? "bracket" : "none"},
                            {"status", merged.status},
                            {"frames", merged.frames},
                            {"still_clipped_sr", merged.still_clipped_sr},
                            {"camera_frames", frame_number - bracket.started_frame},
                            {"ladder_ev", bracket.ladder.ev},
                            {"ladder_asked_frames_before_fit", bracket.lead_frames},
                            {"exposure_latency_frames", bracket.latency_frames},
                            // From the fit frame to the merged map: the camera's frames plus the merge.
                            {"wall_ms", 1000.0 * (monotonicNowS() - bracket.started_s)},
                            // Of that, probelight's own work: each bracket frame's checks and the kept
                            // frame drawn again, then the merge. The rest is waiting for the camera.
                            {"own_ms", 1000.0 * (bracket.own_s + monotonicNowS() - merge_started_s)}};
    FitInputs inputs;
    inputs.view = &bracket.view;
    const ImageRGB8& reference = bracket.reference;
    inputs.read = [&reference](int x, int y) {
      const std::uint8_t* p = reference.row(y) + 3 * x;
      return glm::u8vec3(p[0], p[1], p[2]);
    };
    inputs.hdr = std::move(merged.hdr_cube);
    inputs.exposure = bracket.base;
    inputs.exposure_locked = bracket.exposure_locked;
    return fitLights(frame_number, inputs);
  }

  // lights.white_reference: the tag's white border in the fit's frame says
  // the light on the ground; what the ball's 8-bit map falls short of it goes
  // to its clipped texels (in `corrected`), and from there into the clipped
  // lights the object is shaded with. False (the map stays as it was) when
  // the border cannot be used; the reason is in the report and, when the
  // ball did clip, in a warning.
  bool whiteReference(const ibl::RgbPixelReader& read, const ibl::MirrorBallView& view,
                      const std::vector<float>& validity, ibl::CubeMapRGB& corrected,
                      std::vector<ibl::ClippedLight>& clipped_lights) {
    const AprilTagFamilyHandle family = createAprilTagFamily(inputs_.rig.tag_family);
    if (!family) return false;
    const ibl::WhiteRing ring =
        ibl::tagWhiteRing(family->width_at_border, family->reversed_border, inputs_.rig.tag_size_m);
    ibl::WhiteBorderSettings settings;
    settings.camera_transfer = inputs_.settings.maps.stages.camera_transfer;
    const ibl::WhiteBorderReading reading = ibl::readWhiteBorder(view.camera, view.pose, ring, read, settings);
    const std::vector<std::uint8_t> mask = ibl::clippedTexelMask(view, read, settings.clip_code, corrected.face_size);
    const double clip_level = clipLevel();
    const ibl::CubeMapRGB original = corrected;
    const ibl::WhiteReferenceResult result =
        ibl::correctClippedWithWhiteBorder(corrected, &validity, reading, inputs_.rig.tag_white_albedo, clip_level, &mask);
    const bool used = result.status == ibl::WhiteReferenceStatus::kCorrected;
    // lights.post_reference: the post divides that light between the
    // clipped regions (ibl/post_reference.hpp).
    std::optional<ibl::PostCorrection> post;
    if (used && inputs_.settings.lights.post_reference) {
      ibl::PostReadingSettings post_settings;
      post_settings.camera_transfer = settings.camera_transfer;
      post = ibl::correctClippedWithPost(corrected, original, &validity, clip_level, &mask, reading, inputs_.rig,
                                         view.camera, view.pose, read, post_settings);
      report_.count(std::string("post_") + ibl::toString(post->reading.status));
      if (post->fit.status == ibl::DiffuseFitStatus::kInconsistent)
        log_ << logPrefix(LogPriority::kWarning) << "probelight: the ball's post: " << post->fit.message << "\n";
    }
    if (used) clipped_lights = ibl::clippedLights(corrected, original, &validity, clip_level, &mask);
    report_.count(std::string("white_border_") + ibl::toString(result.status));
    nlohmann::json lights = nlohmann::json::array();
    for (const ibl::ClippedLight& l : clipped_lights)
      lights.push_back({{"direction", {l.direction_w.x, l.direction_w.y, l.direction_w.z}},
                        {"irradiance_rgb", {l.irradiance_rgb.r, l.irradiance_rgb.g, l.irradiance_rgb.b}}});
    report_.extra["white_border"] = {{"border", ibl::toString(reading.status)},
                                     {"correction", ibl::toString(result.status)},
                                     {"message", result.message},
                                     {"patches_lit", reading.patches_lit},
                                     {"patches", reading.patches},
                                     {"clipped_upper_sr", result.clipped_upper_sr},
                                     {"border_irradiance_rgb", {result.border_irradiance_rgb.r, result.border_irradiance_rgb.g,
                                                                result.border_irradiance_rgb.b}},
                                     {"ball_irradiance_rgb", {result.map_irradiance_rgb.r, result.map_irradiance_rgb.g,
                                                              result.map_irradiance_rgb.b}},
                                     {"clipped_lights", lights}};
    if (post) report_.extra["white_border"]["post"] = postCorrectionJson<nlohmann::json>(*post, inputs_.rig);
    if (!used && (result.status == ibl::WhiteReferenceStatus::kBorderDarker ||
                  (result.status == ibl::WhiteReferenceStatus::kBorderUnusable && result.clipped_upper_sr > 0.0)))
      log_ << logPrefix(LogPriority::kWarning)
           << "probelight: the ball's highlights clip and the tag's white border cannot restore them: " << result.message
           << "\n";
    return used;
  }

  // The last good lighting from the state directory: shown from the first
  // frame (the start-up fit then fades from it), and what a long press goes
  // back to. A missing file is normal (first boot); an unreadable one is
  // said, and the kiosk starts without it.
  void loadStoredLighting() {
    const std::string& dir = inputs_.settings.state.dir;
    nlohmann::json state = {{"dir", dir}, {"loaded", false}};
    if (!dir.empty()) {
      std::string error;
      stored_lighting_ = loadLighting(dir, error);
      if (stored_lighting_) {
        showStoredLighting(0.0);
        state["loaded"] = true;
        if (!options_.quiet)
          log_ << "probelight: lighting from " << lightingStatePath(dir).string() << " (" << stored_lighting_->lights.size()
               << " lights)\n";
      } else if (!error.empty()) {
        state["error"] = error;
        log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << error << "; starting without stored lighting\n";
      }
    }
    report_.extra["state"] = state;
  }

  void showStoredLighting(double now_s) {
    light_transition_.retarget(stored_lighting_->lights, now_s);
    // And the fit's clipped lights, followed from the next map update on.
    clipped_lights_ = stored_lighting_->clipped_lights;
    clipped_share_at_fit_ = stored_lighting_->clipped_share_at_fit;
    clipped_share_at_fit_.resize(clipped_lights_.size(), 0.0);
    clipped_exposure_at_fit_ = stored_lighting_->exposure_at_fit;
    setClippedLights(std::vector<double>(clipped_lights_.size(), 1.0));
    lighting_.highlight_direction_w = glm::vec3(stored_lighting_->dominant.direction_w);
    lighting_.highlight_rgb = glm::vec3(stored_lighting_->dominant.rgb);
  }

  // lights.refit_when_light_changes: at each map update (the policy already
  // keeps those to when the ball's image changed, or every max_age_frames),
  // the ground's irradiance in the diffuse map against the one the lights
  // were fitted to; a large change (a lamp switched on or off) starts a
  // recalibration. The read-back is 6 faces of 16^2.
  int checkLightChange(std::uint64_t frame_number) {
    const LightsConfig& config = inputs_.settings.lights;
    if (!config.refit_when_light_changes || machine_.state() != AppState::kRunning || light_transition_.empty())
      return 0;
    std::string error;
    const std::optional<ibl::CubeMapRGB> diffuse = maps_.readDiffuse(error);
    if (!diffuse) return fail(1, error);
    const glm::dvec3 e_up = glm::dvec3(diffuse->sampleBilinear({0.0, 0.0, 1.0})) * 3.14159265358979323846;
    const double before = 0.2126 * lights_fitted_e_up_.r + 0.7152 * lights_fitted_e_up_.g + 0.0722 * lights_fitted_e_up_.b;
    const double now = 0.2126 * e_up.r + 0.7152 * e_up.g + 0.0722 * e_up.b;
    if (before > 0.0 && std::abs(now - before) > config.refit_change_fraction * before) {
      report_.count("refits_for_light_change");
      if (!options_.quiet)
        log_ << "probelight: frame " << frame_number << ": the light changed by " << std::fixed << std::setprecision(0)
             << 100.0 * (now - before) / before << "%: recalibrating\n";
      machine_.onButtonPress();
    }
    return 0;
  }

  // The shadow maps and the ground's fraction follow the lights shown now
  // (fading after a recalibration) and the object: re-rendered only when
  // either changed, so a still scene renders no shadow map.
  int updateShadows() {
    if (!inputs_.settings.lights.shadows || light_transition_.empty()) return 0;
    const std::vector<ibl::ShadowLight> lights = ibl::groundShadowLights(light_transition_.at(frame_time_s_));
    ibl::ShadowCaster caster;
    caster.position_w = glm::dvec2(object_center_w_);
    caster.radius_m = inputs_.settings.object.radius_m;
    const bool same = shadows_drawn_ && lights.size() == shadow_lights_.size() &&
                      std::equal(lights.begin(), lights.end(), shadow_lights_.begin(),
                                 [](const ibl::ShadowLight& a, const ibl::ShadowLight& b) {
                                   return a.direction_w == b.direction_w && a.share_rgb == b.share_rgb &&
                                          a.cone_radius_rad == b.cone_radius_rad;
                                 });
    const int dome_size = static_cast<int>(light_transition_.target().size());
    // Lights below the horizon or too faint never get a pass.
    report_.count("shadow_lights_too_faint", std::max(0, dome_size - static_cast<int>(lights.size())));
    if (same) {
      report_.count("shadow_passes_skipped", static_cast<long long>(lights.size()));
      return 0;
    }
    std::string error;
    {
      StageTimer timer(report_, "shadows");
      if (!ground_shadow_.update(lights, caster, error)) return fail(1, error);
      gpuDone();
    }
    report_.count("shadow_passes_run", ground_shadow_.shadowPassesLastUpdate());
    report_.count("shadow_updates");
    last_shadow_update_frame_ = frames_done_ - 1;  // the frame being processed
    shadow_lights_ = lights;
    shadows_drawn_ = true;
    return 0;
  }

  int renderAndPresent(const tracking::TagTrackResult& track, const std::string& status, std::uint64_t frame_number,
                       bool log_status_change = true) {
    const CameraIntrinsics& camera = inputs_.camera;
    std::string error;
    kept_frame_status_.reset();  // the display's frame is drawn anew
    {
      StageTimer timer(report_, "render");
      display_->beginFrame();
      compositor_.drawCameraBackground(frame_texture_);
      // The shadow first: the object then covers the part of it under itself.
      if (track.found && have_maps_ && !ground_shadow_.drawOnCameraImage(camera, track.pose, frame_texture_, error))
        return fail(1, error);
      // Before the first maps exist the object would be black: leave it out.
      if (track.found && have_maps_ &&
          !compositor_.drawSphereObject(camera, track.pose, object_center_w_, inputs_.settings.object.radius_m,
                                        material_, lighting_, maps_, error))
        return fail(1, error);
      if (!status.empty()) {
        const auto& rgba = overlay_.render(status, camera.width_px, camera.height_px);
        if (!compositor_.drawOverlayRGBA(rgba.data(), camera.width_px, camera.height_px, error)) return fail(1, error);
      }
      gpuDone();
    }
    return presentFrame(status, frame_number, log_status_change);
  }

  // Shows the display's frame (drawn by renderAndPresent, now or for an
  // earlier frame) as frame `frame_number`.
  int presentFrame(const std::string& status, std::uint64_t frame_number, bool log_status_change) {
    std::string error;
    if (!status.empty()) report_.count("frames_with_status");
    if (log_status_change && status != last_logged_status_ && !options_.quiet) {
      log_ << "probelight: frame " << frame_number << ": " << (status.empty() ? "tracking" : status) << "\n";
      last_logged_status_ = status;
    }
    {
      StageTimer timer(report_, "present");
      if (frameLimit() != 0 && frames_done_ == frameLimit())
        if (auto* headless = dynamic_cast<HeadlessDisplay*>(display_.get())) headless->keepNextFrame();
      if (!display_->present(frame_number, error)) return fail(1, error);
    }
    {
      // systemd: ready once the first frame is shown, then the watchdog
      // from here, so a hung camera or GPU stops the pings.
      notifier_.ready("showing frames from " + source_->name() + " on " + display_->describe());
      notifier_.frameShown();
      if (status != last_notified_status_) {
        notifier_.status(status.empty() ? "tracking" : status);
        last_notified_status_ = status;
      }
    }
    return 0;
  }

  int writeReport(double elapsed_s) {
    report_.extra["source"] = source_->name();
    report_.extra["display"] = display_->describe();
    report_.extra["gl"] = capabilities_.summary();
    report_.extra["state_at_end"] = toString(machine_.state());
    report_.extra["map_storage"] = maps_.storageDescription();
    report_.extra["map_updates"] = mapUpdatesJson();
    // Frames per tracking status, and the last frame the tag was not usable.
    report_.extra["tag_status"] = {{"frames", tag_status_frames_}, {"last_problem", last_tag_problem_}};
    report_.extra["probe_refinement"] = probeRefinementJson();
    report_.extra["camera"] = cameraJson();
    // Shadow maps are made only when the lights (fading after a fit) or the
    // object change: passes run and skipped (a skipped pass is a light whose
    // map from an earlier frame still holds), and the last frame that made any.
    report_.extra["shadows"] = {{"enabled", inputs_.settings.lights.shadows},
                                {"depth_storage", inputs_.settings.lights.shadows ? ground_shadow_.depthStorageDescription() : ""},
                                {"passes_run", report_.counter("shadow_passes_run")},
                                {"passes_skipped", report_.counter("shadow_passes_skipped")},
                                {"updates", report_.counter("shadow_updates")},
                                {"last_update_frame", last_shadow_update_frame_}};
    const nlohmann::json json = report_.toJson(static_cast<long long>(frames_done_), elapsed_s);
    const std::filesystem::path report_path = std::filesystem::path(options_.out_dir) / "report.json";
    std::ofstream out(report_path);
    out << json.dump(2) << "\n";
    if (!out) return fail(1, "cannot write " + report_path.string());
    if (!options_.quiet)
      log_ << "probelight: " << frames_done_ << " frames in " << std::fixed << std::setprecision(1) << elapsed_s
           << " s; report: " << report_path.string() << "\n";
    return 0;
  }

  // probe_refinement: fits this frame's ball outline to the image and moves
  // the rig correction toward what the fit implies (tracking/probe_edge_fit.hpp).
  // Only on a ball fully in view and big enough to be worth a map.
  void refineProbe(const ibl::MirrorBallView& view, const ibl::ProbeOutline& outline, const LumaView& luma) {
    const ProbeRefinementConfig& config = inputs_.settings.probe_refinement;
    if (!config.enabled || !outline.valid || !outline.fully_in_image ||
        outline.radius_px < inputs_.settings.map_updates.min_probe_radius_px)
      return;
    StageTimer timer(report_, "probe_refine");
    const tracking::ProbeEdgeFit fit = tracking::fitProbeOutlineToEdges(
        luma.data, luma.width, luma.height, luma.stride, outline,
        inputs_.rig.probe_reflectance, inputs_.settings.maps.stages.camera_transfer);
    if (!fit.ok) {
      ++probe_fits_refused_;
      probe_fit_last_refusal_ = fit.reason;
      return;
    }
    ++probe_fits_;
    probe_fit_shift_px_.add(glm::length(fit.shift_px));
    const glm::dvec3 implied = tracking::probeCenterForImageShift(view.pose, view.camera, view.center_w, fit.shift_px);
    probe_center_offset_w_ += config.weight * (implied - view.center_w);
    probe_radius_scale_ *= 1.0 + config.weight * (fit.radius_scale - 1.0);
  }

  nlohmann::json cameraJson() const {
    nlohmann::json out = {{"frame_upload", passes::toString(frame_texture_.lastPath())},
                           {"losses", report_.counter("camera_losses")},
                           {"reconnects", report_.counter("camera_reconnects")},
                           {"reconnect_failures", report_.counter("camera_reconnect_failures")},
                           {"exposure_locks", report_.counter("exposure_locks")},
                           {"exposure_at_last_fit", exposure_at_last_fit_}};
    if (!frame_texture_.dmabufImportProblem().empty()) out["dmabuf_import_problem"] = frame_texture_.dmabufImportProblem();
    if (!last_camera_problem_.empty()) out["last_problem"] = last_camera_problem_;
    recordSeries(out, "exposure_us", exposure_us_);
    recordSeries(out, "analogue_gain", analogue_gain_);
    return out;
  }

  nlohmann::json probeRefinementJson() const {
    nlohmann::json json = {{"enabled", inputs_.settings.probe_refinement.enabled},
                           {"fits", probe_fits_},
                           {"refused", probe_fits_refused_},
                           {"center_offset_mm", {1000.0 * probe_center_offset_w_.x, 1000.0 * probe_center_offset_w_.y,
                                                 1000.0 * probe_center_offset_w_.z}},
                           {"radius_scale", probe_radius_scale_}};
    if (!probe_fit_shift_px_.empty()) json["fit_shift_px_median"] = probe_fit_shift_px_.median();
    if (!probe_fit_last_refusal_.empty()) json["last_refusal"] = probe_fit_last_refusal_;
    return json;
  }

  // The report names the diffuse stage after the method that ran.
  const char* diffuseStageName() const {
    return inputs_.settings.maps.diffuse_method == DiffuseMethod::kSH9 ? "diffuse_sh9" : "diffuse_blur";
  }

  // glFinish after a GPU stage, so that its timer measures the GPU's work.
  void gpuDone() const {
    if (inputs_.settings.gpu_finish) glFinish();
  }
  std::uint64_t frameLimit() const { return static_cast<std::uint64_t>(options_.frames); }
  int fail(int status, const std::string& message) {
    log_ << logPrefix(LogPriority::kError) << "probelight: " << message << "\n";
    return status;
  }

  const RunOptions& options_;
  std::ostream& log_;
  LoadedInputs inputs_;

  std::shared_ptr<const sim::World> world_;  // only with --source sim: the truth
  std::unique_ptr<FrameSource> source_;
  std::unique_ptr<Display> display_;  // owns the GL context: declared before the GL objects below
  gles::Capabilities capabilities_;
  passes::CameraFrameTexture frame_texture_;
  passes::EnvironmentMaps maps_;
  passes::ObjectCompositor compositor_;
  std::unique_ptr<tracking::TagTracker> tracker_;
  std::unique_ptr<tracking::TagTracker> bracket_tracker_;  // follows the tag through each bracket's frames
  std::unique_ptr<tracking::PoseSmoother> smoother_;
  passes::GroundShadow ground_shadow_;
  LightTransition light_transition_;
  double frame_time_s_ = 0.0;  // of the frame being processed, from its timestamp
  glm::dvec3 lights_fitted_e_up_{0.0};  // the ground's irradiance when the lights were last fitted
  std::vector<ibl::ShadowLight> shadow_lights_;  // what the shadow maps show
  bool shadows_drawn_ = false;
  std::uint64_t last_shadow_update_frame_ = 0;
  std::optional<StoredLighting> stored_lighting_;  // loaded from the state directory at start-up
  ServiceNotifier notifier_;
  std::string last_notified_status_;
  std::map<std::string, long long> tag_status_frames_;
  nlohmann::json last_tag_problem_;  // null until a frame's tag is not usable
  // probe_refinement's correction of rig.yaml's ball, and its record.
  glm::dvec3 probe_center_offset_w_{0.0};
  double probe_radius_scale_ = 1.0;
  long long probe_fits_ = 0, probe_fits_refused_ = 0;
  SampleSeries probe_fit_shift_px_;
  std::string probe_fit_last_refusal_;
  std::unique_ptr<ButtonSource> button_;
  std::unique_ptr<StatusLed> status_led_;

  ibl::SurfaceMaterial material_;
  ibl::SceneLighting lighting_;  // no highlight until the first calibration
  glm::dvec3 object_center_w_{0.0};
  LightingStateMachine machine_;
  MapUpdatePolicy map_policy_;
  std::optional<ibl::MirrorBallView> maps_view_;  // the view the current maps were made from
  std::map<std::string, long long> map_update_causes_;
  std::map<std::string, long long> map_skip_reasons_;
  SampleSeries center_shift_px_, radius_change_px_, rotation_change_deg_, image_change_code_;
  SampleSeries truth_center_shift_px_;
  std::optional<glm::dvec2> previous_truth_center_px_;
  nlohmann::json truth_checks_ = nlohmann::json::array();
  RunReport report_;
  StatusOverlay overlay_;
  bool have_maps_ = false;
  std::uint64_t frames_done_ = 0;
  std::string last_logged_status_;

  // The camera: lost and reconnecting, exposure lock, and what the frames said.
  static constexpr int kTimeoutsBeforeReconnect = 5;  // of 2 s each
  ReconnectBackoff reconnect_;
  std::string last_camera_problem_;
  tracking::TagTrackResult last_track_;  // redrawn over the last frame while the camera is lost
  std::uint64_t last_frame_number_ = 0;
  std::uint64_t frames_since_camera_start_ = 0;
  bool exposure_locked_ = false;
  SampleSeries exposure_us_, analogue_gain_;
  double last_exposure_us_ = 0.0, last_analogue_gain_ = 0.0;
  nlohmann::json exposure_at_last_fit_;  // null until a fit
  std::optional<PendingBracket> bracket_;  // an exposure bracket being taken
  std::optional<EarlyLadder> early_ladder_;  // a ladder asked for ahead of its fit frame
  int bracket_lead_frames_ = 2;
  // The status the display's frame was last drawn with as a kept frame
  // (reset by every drawing): a kept frame with the same status is shown
  // again without drawing it.
  std::optional<std::string> kept_frame_status_;
  struct Settling {
    FrameSource::ManualExposure base;  // the exposure to come back to
    int frames_waited = 0;
  };
  std::optional<Settling> settling_;  // after a bracket, until the exposure is back
  // The last fit's clipped lights, and what they are followed against.
  std::vector<ibl::ClippedLight> clipped_lights_;
  std::vector<double> clipped_share_at_fit_;
  double clipped_exposure_at_fit_ = 1.0;
};

}  // namespace

int runKiosk(const RunOptions& options, std::ostream& log) { return Kiosk(options, log).run(); }

}  // namespace probelight
