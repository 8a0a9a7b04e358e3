#include "app/kiosk.hpp"

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <optional>
#include <thread>

#include "app/app_settings.hpp"
#include "app/camera_link.hpp"
#include "app/heap_release.hpp"
#include "app/resource_log.hpp"
#include "app/service_notify.hpp"
#include "app/shutdown_request.hpp"
#include "app/simulated_world.hpp"
#include "capture/frame_recorder.hpp"
#include "capture/frame_recording.hpp"
#include "capture/image_frame_source.hpp"
#include "capture/libcamera_source.hpp"
#include "capture/recording_frame_source.hpp"
#include "capture/rgb_image_io.hpp"
#include "capture/scheduled_camera_loss.hpp"
#include "capture/sim_frame_source.hpp"
#include "config/camera_file.hpp"
#include "config/config_reader.hpp"
#include "config/rig_file.hpp"
#include "core/log_priority.hpp"
#include "core/monotonic_clock.hpp"
#include "display/display.hpp"
#include "display/window_display.hpp"
#include "gles/capabilities.hpp"
#include "input/button_source.hpp"
#include "input/status_led.hpp"
#include "sim/world.hpp"
#include "stages/compose_stage.hpp"
#include "stages/blur_match_stage.hpp"
#include "stages/lamp_exposure.hpp"
#include "stages/motion_match_stage.hpp"
#include "stages/noise_match_stage.hpp"
#include "stages/response_match_stage.hpp"
#include "stages/frame_context.hpp"
#include "stages/lights_stage.hpp"
#include "stages/maps_stage.hpp"
#include "stages/run_report.hpp"
#include "stages/shadows_stage.hpp"
#include "stages/stage_settings.hpp"
#include "stages/track_stage.hpp"
#include "stages/truth_monitor.hpp"
#include "stages/upload_stage.hpp"

namespace probelight {

namespace {

namespace fs = std::filesystem;

struct LoadedInputs {
  AppSettings settings;
  CameraIntrinsics camera;
  RigGeometry rig;
  bool camera_from_file = false;
  bool rig_from_file = false;
};

// Reads every file the run needs before anything starts, so that a bad one
// costs nothing but its one-line message. Throws config::ConfigError.
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
  if (!options.model_path.empty()) inputs.settings.object.model_path = options.model_path;
  if (!options.camera_id.empty()) inputs.settings.camera.id = options.camera_id;
  return inputs;
}

// One `probelight run`: the seams (camera, display, button) and the stages,
// wired; each frame walks the stages in the data path's order.
class Kiosk {
 public:
  Kiosk(const RunOptions& options, std::ostream& log) : options_(options), log_(log) {}

  Status run() {
    PROBELIGHT_TRY(setUp());
    installShutdownHandlers();
    loop_start_s_ = monotonicNowS();
    Status status = frameLoop();
    // A bracket the run's end cut short (its frame limit, its stream, a
    // signal): the lights are fitted from what it has, and kept.
    if (status.isOk()) status = lights_->finishPendingBracket(last_frame_number_, *maps_);
    notifier_.stopping();
    const double elapsed_s = monotonicNowS() - loop_start_s_;
    source_->stop();
    PROBELIGHT_TRY(status);
    if (std::string error; !display_->finish(error)) return Status::runtimeFailure(error);
    PROBELIGHT_TRY(writeReport(elapsed_s));
    return writeCapture();
  }

 private:
  // capture -> upload -> track -> maps -> lights -> shadows -> compose -> display
  Status frameLoop() {
    while (frameLimit() == 0 || frames_done_ < frameLimit()) {
      if (const int signal_number = shutdownSignal(); signal_number != 0) {
        log_ << logPrefix(LogPriority::kInfo) << "probelight: " << (signal_number == SIGTERM ? "SIGTERM" : "SIGINT")
             << ": stopping after " << frames_done_ << " frames\n";
        return Status::ok();
      }
      pollButton();
      if (quit_requested_) {
        log_ << logPrefix(LogPriority::kInfo) << "probelight: quit from the " << display_->name() << ": stopping after "
             << frames_done_ << " frames\n";
        return Status::ok();
      }
      status_led_->set(ledLitAt(ledPatternFor(lights_->recalibrating(), camera_->lost()), monotonicNowS()));
      if (camera_->lost()) {
        PROBELIGHT_TRY(whileCameraLost());
        continue;
      }
      FrameLease lease;
      const CameraEvent event = camera_->next(lease);
      if (event == CameraEvent::kEnded) return Status::ok();
      // The report is still written (the caller does), with what ran.
      if (event == CameraEvent::kFailed) return Status::badInput(source_->name() + ": " + source_->lastError());
      if (event == CameraEvent::kLost) lights_->onCameraLost();
      if (event == CameraEvent::kNoFrame) PROBELIGHT_TRY(whileCameraSilent());
      if (event != CameraEvent::kFrame) continue;
      recordFrame(*lease);
      FrameContext ctx(*lease, frames_done_++);
      ctx.frames_since_camera_start = camera_->framesSinceStart();
      PROBELIGHT_TRY(processFrame(ctx));
      if (heap_release_.releaseAfter(heavyEventsSoFar()) && releaseFreeHeapToSystem())
        report_.count("heap_releases");
      if (resources_.due(frames_done_))
        resources_.write(frames_done_, monotonicNowS() - loop_start_s_, readProcessResources(),
                         gles::countLiveGlObjects());
    }
    return Status::ok();
  }

  // The display's save key (a window's S): the camera's own frame, as it
  // came and converted to RGB, beside the composite the display saves:
  // OUT/camera_NNNNNN.png, for calibrate-camera's views or analyze. A
  // failed write is said and the run goes on.
  void saveCameraFrame(const FrameContext& ctx) {
    camera_frame_save_due_ = false;
    const std::string path = (fs::path(options_.out_dir) / numberedPngName("camera", ctx.number)).string();
    std::string error;
    if (!writeRgbPng(path, ctx.frame.toRgb(), error)) {
      log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << error << "\n";
      return;
    }
    report_.count("camera_frames_saved");
    log_ << "probelight: S: saving the camera's frame as " << path << "\n";
  }

  // The events whose temporaries dwarf a frame's (heap_release.hpp).
  long long heavyEventsSoFar() const {
    return report_.counter("calibrations_completed") + report_.counter("calibrations_failed") +
           report_.counter("button_long_presses_restored") + report_.counter("refits_for_light_change") +
           report_.counter("camera_reconnects");
  }

  Status processFrame(FrameContext& ctx) {
    if (camera_frame_save_due_) saveCameraFrame(ctx);
    if (!frameFitsCalibration(ctx.frame)) return Status::ok();
    // A bracket's frames, and those after it still at its exposures, are not
    // the picture's: the last frame stays on screen.
    if (const FrameAdmission admission = lights_->admit(ctx); !admission.run_pipeline) {
      PROBELIGHT_TRY(showKeptFrame(ctx.number, admission.kept_status));
      return lights_->afterKeptFrame(ctx, *maps_);
    }
    PROBELIGHT_TRY(upload_->run(ctx));
    if (const std::string notice = upload_->takeNotice(); !notice.empty())
      log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << notice << "\n";
    track_->run(ctx);
    maps_->setLightsFittedAt(lights_->clipReference());
    PROBELIGHT_TRY(maps_->run(ctx, upload_->texture()));
    PROBELIGHT_TRY(lights_->run(ctx, *maps_));
    PROBELIGHT_TRY(shadows_->run(ctx.number, lights_->domeAt(ctx.time_s), lights_->domeSize()));
    response_->run(ctx.frame, *maps_, ctx.number);
    noise_->run(ctx.track, ctx.frame, ctx.number);
    blur_->run(ctx.track, ctx.frame);
    motion_->run(ctx.track, ctx.frame.metadata, ctx.time_s);
    lamp_exposure_->run(ctx.track.found && maps_->haveMaps(), ctx.track.pose, ctx.frame,
                        lights_->roomGroundIrradiance(), ctx.time_s);
    // A display with keys says them in the status bar for its first
    // seconds (beside whatever else the status says).
    if (const std::string hint = display_->startupHint();
        !hint.empty() && monotonicNowS() - loop_start_s_ < kStartupHintSeconds)
      ctx.status = ctx.status.empty() ? hint : ctx.status + "  |  " + hint;
    PROBELIGHT_TRY(show(ctx.track, ctx.status, ctx.number));
    last_track_ = ctx.track;
    last_frame_number_ = ctx.number;
    if (truth_) truth_->observe(ctx, *maps_, lights_->sceneLighting());
    if (!options_.capture_dir.empty()) last_pipeline_frame_ = ctx.frame.toRgb();
    return Status::ok();
  }

  // The calibration belongs to one resolution: a frame of another would put
  // the object and the ball in the wrong place. Skipped, the state kept.
  bool frameFitsCalibration(const FrameBuffer& frame) {
    const CameraIntrinsics& camera = inputs_.camera;
    if (frame.width_px == camera.width_px && frame.height_px == camera.height_px) return true;
    report_.count("frames_wrong_size");
    log_ << "probelight: " << frame.metadata.origin << ": frame is " << frame.width_px << "x" << frame.height_px
         << " but the camera calibration is " << camera.width_px << "x" << camera.height_px << "; frame skipped\n";
    return false;
  }

  // The compose stage draws the frame into the display's drawable, which
  // then shows it.
  Status show(const tracking::TagTrackResult& track, const std::string& status, std::uint64_t frame_number,
              bool log_status_change = true) {
    kept_frame_status_.reset();  // the display's frame is drawn anew
    display_->beginFrame();
    compose_->setResponseGain(response_->gain());
    compose_->setSensorNoise(noise_->match());
    compose_->setBlur(blur_->edgeSigmaPx());
    compose_->setMotionSmear(motion_->smearPx());
    compose_->setRoomLight(lights_->roomGroundIrradiance());
    compose_->setExposureGain(lamp_exposure_->gain());
    PROBELIGHT_TRY(compose_->draw(track, status, upload_->texture(), *maps_, *shadows_, lights_->sceneLighting()));
    return present(status, frame_number, log_status_change);
  }

  // A frame of (or just after) a bracket: not shown; the last frame stays,
  // with `status`. Every frame is accounted for in every stage: these skip it.
  Status showKeptFrame(std::uint64_t frame_number, const std::string& status) {
    static const std::string kReason = "exposure_bracket";
    report_.count("frames_in_bracket");
    upload_->skip(kReason);
    track_->skip(kReason);
    maps_->skip(kReason);
    response_->skip(kReason);
    noise_->skip(kReason);
    blur_->skip(kReason);
    motion_->skip(kReason);
    lamp_exposure_->skip(kReason);
    // The display's frame already holds the kept frame with this status
    // (nothing was drawn since): it is shown again, not drawn again.
    if (kept_frame_status_ == status) {
      compose_->skip("kept_frame_unchanged");
      return present(status, frame_number, false);
    }
    PROBELIGHT_TRY(show(last_track_, status, frame_number, false));
    kept_frame_status_ = status;
    return Status::ok();
  }

  // Shows the display's frame (drawn now, or for an earlier frame) as frame
  // `frame_number`.
  Status present(const std::string& status, std::uint64_t frame_number, bool log_status_change) {
    if (!status.empty()) report_.count("frames_with_status");
    if (log_status_change && status != last_logged_status_ && !options_.quiet) {
      log_ << "probelight: frame " << frame_number << ": " << (status.empty() ? "tracking" : status) << "\n";
      last_logged_status_ = status;
    }
    {
      StageTimer timer(report_, "present");
      if (frameLimit() != 0 && frames_done_ == frameLimit()) display_->keepNextFrame();
      std::string error;
      if (!display_->present(frame_number, error)) return Status::runtimeFailure(error);
      report_.recordFrameShown(monotonicNowS());
    }
    // systemd: ready once the first frame is shown, then the watchdog from
    // here, so a hung camera or GPU stops the pings.
    notifier_.ready("showing frames from " + source_->name() + " on " + display_->describe());
    notifier_.frameShown();
    if (status != last_notified_status_) {
      notifier_.status(status.empty() ? "tracking" : status);
      last_notified_status_ = status;
    }
    return Status::ok();
  }

  // The last frame stays on screen with a message (and the watchdog keeps
  // being fed: the service is healthy, the camera is not) until a reconnect
  // attempt, when due, succeeds.
  Status whileCameraLost() {
    // A bracket the loss cut short: the lights are fitted from what it has.
    PROBELIGHT_TRY(lights_->finishPendingBracket(last_frame_number_, *maps_));
    std::string status;
    if (camera_->tryReconnect(status)) return Status::ok();
    if (!upload_->texture().empty())
      PROBELIGHT_TRY(show(last_track_, status, last_frame_number_, false));  // the countdown is not logged
    else
      notifier_.frameShown();  // nothing to show yet; the service itself is alive
    std::this_thread::sleep_for(camera_->idleWait());
    return Status::ok();
  }

  // The camera is open but delivers nothing (a stalled sensor, a driver
  // gone without a word): the last frame stays, saying so, and the
  // watchdog is fed, since the service itself is alive. The camera link
  // re-opens the camera after a long silence (camera_link.hpp); before
  // that, the watchdog must not restart the whole service for it (the
  // shipped unit's WatchdogSec is as long as that silence).
  Status whileCameraSilent() {
    const std::string status =
        "No frame from the camera for " + std::to_string(camera_->silentSeconds()) + " s: waiting";
    if (!upload_->texture().empty()) return show(last_track_, status, last_frame_number_, false);
    notifier_.frameShown();
    return Status::ok();
  }

  // The button (--button), and the display's own keys (a desktop window's
  // R, long R, and its quit) as the same presses.
  void pollButton() {
    std::vector<ButtonEvent::Kind> presses;
    for (const ButtonEvent& event : button_->poll()) presses.push_back(event.kind);
    const DisplayInput input = display_->pollInput();
    presses.insert(presses.end(), input.button.begin(), input.button.end());
    if (input.quit) quit_requested_ = true;
    if (input.saves > 0) camera_frame_save_due_ = true;
    for (const ButtonEvent::Kind kind : presses) {
      if (kind == ButtonEvent::Kind::kLongPress)
        lights_->onLongPress();
      else if (lights_->onButtonPress())
        maps_->requestFreshMap();  // the lights are fitted from a map made now
    }
  }

  // --- set-up ---------------------------------------------------------------

  static Status createFolder(const std::string& path, const char* flag) {
    std::error_code ec;
    fs::create_directories(path, ec);
    if (ec || !fs::is_directory(path))
      return Status::badInput(path + ": cannot create the folder (" + flag + ")" +
                              (ec ? ": " + ec.message() : std::string()));
    return Status::ok();
  }

  // Reads every file, then opens source, display, stages and button, in that
  // order, so that a bad file costs nothing but its message.
  Status setUp() {
    try {
      inputs_ = loadInputs(options_);
    } catch (const config::ConfigError& error) {
      return Status::badInput(error.what());
    }
    // Made now, so that a folder that cannot be made costs nothing but its
    // message; --out holds report.json whichever the display.
    PROBELIGHT_TRY(createFolder(options_.out_dir, "--out"));
    if (!options_.capture_dir.empty()) PROBELIGHT_TRY(createFolder(options_.capture_dir, "--capture"));
    PROBELIGHT_TRY(checkRecordingFolder());
    PROBELIGHT_TRY(makeSource());
    const AppSettings& settings = inputs_.settings;
    std::string error;
    WindowDisplaySettings window;
    window.long_press_ms = settings.button.gpio.debounce.long_press_ms;
    window.log = &log_;
    display_ = makeDisplay(options_.display, options_.out_dir, settings.save_every, settings.display.kms, window, error);
    if (!display_ || !display_->open(inputs_.camera.width_px, inputs_.camera.height_px, error))
      return Status::runtimeFailure(error);
    capabilities_ = gles::probeCapabilities();
    if (settings.maps.force_8bit) capabilities_ = capabilities_.withoutExtensions();
    PROBELIGHT_TRY(makeStages());
    PROBELIGHT_TRY(openButtonAndLed());
    resources_ = ResourceLog(settings.resources_every_frames);
    if (!resources_.open((fs::path(options_.out_dir) / "resources.csv").string(), error))
      return Status::runtimeFailure(error);
    // A camera that cannot give camera.yaml's size or the format asked for
    // is a configuration problem: exit status 2, which the service's unit
    // does not restart (a restart would only fail again).
    if (!source_->start(error))
      return options_.source == "images" || source_->refusedItsSettings() ? Status::badInput(error)
                                                                           : Status::runtimeFailure(error);
    PROBELIGHT_TRY(beginRecording());
    // Start-up lines, logged under --quiet too (the service's journal), once
    // every file has been read: a bad file is its one line of error alone.
    log_ << "probelight: " << display_->describe() << ": " << capabilities_.summary() << "\n";
    if (!source_->streamDescription().empty())
      log_ << "probelight: " << source_->name() << ": " << source_->streamDescription() << "\n";
    // Once, at the first start: a reconnect meets the same camera.
    if (const std::string warning = source_->focusWarning(); !warning.empty())
      log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << warning << "\n";
    lights_->loadStoredLighting();
    if (const std::string warning = maps_->loadStoredProbe(settings.state.dir); !warning.empty())
      log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << warning << "; starting without it\n";
    return Status::ok();
  }

  Status makeSource() {
    const AppSettings& settings = inputs_.settings;
    if (options_.source == "images") {
      source_ = std::make_unique<ImageFrameSource>(options_.images);
    } else if (options_.source == "recording") {
      source_ = std::make_unique<RecordingFrameSource>(options_.recording_dir);
      PROBELIGHT_TRY(makeReplayedWorld());
    } else if (options_.source == "libcamera") {
      LibcameraSettings camera;
      camera.camera_id = settings.camera.id;
      camera.width_px = inputs_.camera.width_px;  // the calibrated size
      camera.height_px = inputs_.camera.height_px;
      camera.pixel_format = settings.camera.pixel_format;
      camera.lens_position_dioptres = inputs_.camera.lens_position_dioptres;
      source_ = std::make_unique<LibcameraSource>(camera);
    } else {
      PROBELIGHT_TRY(makeSimulatedCamera());
    }
    // Injected losses wrap any source; replayed frames then reconnect as a
    // camera does (a folder that really fails still ends the run).
    const bool losses_injected = settings.faults.camera_loss_every_frames > 0;
    if (losses_injected)
      source_ = std::make_unique<ScheduledCameraLoss>(std::move(source_),
                                                      static_cast<std::uint64_t>(settings.faults.camera_loss_every_frames),
                                                      settings.faults.camera_loss_failed_restarts);
    camera_ = std::make_unique<CameraLink>(*source_, settings.camera.reconnect_max_interval_s,
                                           (options_.source != "images" && options_.source != "recording") || losses_injected,
                                           report_, log_);
    return Status::ok();
  }

  // Which file or flag a simulator's complaint is about ("" when the values
  // are the built-in ones), so that its one line names it.
  std::string simulatorInputName(const std::string& message) const {
    auto startsWith = [&](const char* prefix) { return message.rfind(prefix, 0) == 0; };
    auto setting = [&](const std::string& flag_value, const char* flag, const char* field) -> std::string {
      if (!flag_value.empty()) return std::string(flag) + ": ";
      if (!options_.config_path.empty()) return options_.config_path + ": field '" + field + "': ";
      return "";
    };
    if (startsWith("environment")) return setting(options_.sim_env, "--env", "sim.env");
    if (startsWith("camera_path")) return setting(options_.sim_path, "--path", "sim.camera_path");
    if (startsWith("rig.") && inputs_.rig_from_file) return options_.rig_path + ": the simulator cannot stage it: ";
    if (startsWith("camera") && inputs_.camera_from_file) return options_.camera_path + ": the simulator cannot use it: ";
    if (startsWith("random camera pose")) return inputs_.rig_from_file ? options_.rig_path + ": " : "";
    return "";
  }

  // A replayed recording of the simulated camera: its world rebuilt from
  // recording.json and the recording's own camera.yaml and rig.yaml, for
  // the truth alone (no frame is rendered), so that the replay's report
  // measures the pipeline as the live run's did. A camera's recording has
  // no simulation, and a bad recording.json is the source's to say.
  Status makeReplayedWorld() {
    RecordingHeader header;
    if (!readRecordingHeader(options_.recording_dir, header).isOk() || !header.simulation) return Status::ok();
    const fs::path dir = options_.recording_dir;
    sim::SceneConfig scene = sim::defaultScene();
    try {
      scene.camera = config::loadCameraFile((dir / "camera.yaml").string());
      scene.rig = config::loadRigFile((dir / "rig.yaml").string());
    } catch (const config::ConfigError& error) {
      return Status::badInput(error.what());
    }
    applySimulation(*header.simulation, scene);
    try {
      world_ = std::make_shared<const sim::World>(scene);
    } catch (const sim::SceneError& error) {
      return Status::badInput((dir / kRecordingHeaderFile).string() + ": field 'simulation': " + error.what());
    }
    simulation_ = header.simulation;
    return Status::ok();
  }

  Status makeSimulatedCamera() {
    const AppSettings& settings = inputs_.settings;
    sim::SceneConfig scene = sim::defaultScene();
    if (inputs_.camera_from_file) scene.camera = inputs_.camera;
    if (inputs_.rig_from_file) scene.rig = inputs_.rig;
    // The simulated camera and rig are what the pipeline is told: a perfect
    // calibration, so that the errors measured are the pipeline's own
    // (unless sim.ball_offset says the real ball is elsewhere).
    inputs_.camera = scene.camera;
    inputs_.rig = scene.rig;
    const RecordedSimulation simulation = simulationOf(settings.sim);
    applySimulation(simulation, scene);
    try {
      world_ = std::make_shared<const sim::World>(scene);
    } catch (const sim::SceneError& error) {
      return Status::badInput(simulatorInputName(error.what()) + error.what());
    }
    simulation_ = simulation;
    SimCameraOptions camera_options;
    camera_options.layout = PixelLayout::kRgb8;
    for (const CameraFormatInfo& format : cameraFormats())
      if (settings.sim.pixel_format == format.config_name) camera_options.layout = format.layout;
    camera_options.lost_at_frame = settings.sim.camera_lost_at_frame;
    camera_options.failed_restarts = settings.sim.camera_lost_restarts;
    camera_options.silent_at_frame = settings.sim.camera_silent_at_frame;
    camera_options.silent_s = settings.sim.camera_silent_s;
    camera_options.min_exposure_us = settings.sim.min_exposure_us;
    camera_options.min_exposure_reported = settings.sim.min_exposure_reported;
    camera_options.exposure_controllable = settings.sim.exposure_control;
    camera_options.exposure_stops = settings.sim.exposure_stops;
    camera_options.response_shift_from_frame = settings.sim.response_shift_from_frame;
    camera_options.response_shift_until_frame = settings.sim.response_shift_until_frame;
    camera_options.exposure_shift_stops = settings.sim.exposure_shift_stops;
    camera_options.white_balance_shift_red = settings.sim.white_balance_shift_red;
    camera_options.white_balance_shift_blue = settings.sim.white_balance_shift_blue;
    camera_options.motion_blur = settings.sim.motion_blur;
    camera_options.lens_position_dioptres = inputs_.camera.lens_position_dioptres;
    camera_options.lens_control = settings.sim.lens_control;
    source_ = std::make_unique<SimFrameSource>(world_, frameLimit(), settings.sim.camera_buffers, camera_options);
    return Status::ok();
  }

  Status makeStages() {
    const AppSettings& settings = inputs_.settings;
    SceneObject object;
    PROBELIGHT_TRY(sceneObjectFromConfig(settings, object));
    if (object.isModel())
      for (const std::string& warning : object.model->warnings)
        log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << warning << "\n";
    upload_ = std::make_unique<UploadStage>(report_, settings.gpu_finish);
    track_ = std::make_unique<TrackStage>(settings, inputs_.rig, inputs_.camera, report_);
    maps_ = std::make_unique<MapsStage>(settings, inputs_.rig, object.readsGlossy(glossyExponents(settings)),
                                        settings.maps.merge_views, report_);
    lights_ = std::make_unique<LightsStage>(settings, inputs_.rig, inputs_.camera, *source_, report_, log_);
    shadows_ = std::make_unique<ShadowsStage>(settings, object.shape, report_);
    compose_ = std::make_unique<ComposeStage>(object, inputs_.camera, inputs_.rig, settings.maps.stages.camera_transfer,
                                              report_, settings.gpu_finish);
    compose_->setVirtualLamp(settings.virtual_lamp);
    if (settings.camera_match.bloom) {
      // The lens's glare spread, from degrees of the field to the frame's pixels.
      const double sigma_rad = settings.camera_match.bloom_sigma_deg * M_PI / 180.0;
      compose_->setBloom(inputs_.camera.fx_px * std::tan(sigma_rad));
    }
    response_ = std::make_unique<ResponseMatchStage>(settings.camera_match, report_);
    noise_ = std::make_unique<NoiseMatchStage>(settings.camera_match, inputs_.camera, inputs_.rig, report_);
    blur_ = std::make_unique<BlurMatchStage>(settings.camera_match, inputs_.camera, inputs_.rig,
                                             settings.maps.stages.camera_transfer, report_);
    motion_ = std::make_unique<MotionMatchStage>(settings.camera_match, inputs_.camera,
                                                 object.shape.boundingCentre(), report_);
    lamp_exposure_ = std::make_unique<LampExposureStage>(settings.virtual_lamp.enabled, settings.virtual_lamp.lamp,
                                                         inputs_.camera, settings.maps.stages.camera_transfer, report_);
    if (world_) truth_ = std::make_unique<TruthMonitor>(world_, report_);
    PROBELIGHT_TRY(upload_->init(capabilities_));
    PROBELIGHT_TRY(maps_->init(capabilities_));
    PROBELIGHT_TRY(compose_->init(capabilities_, maps_->maps().storage()));
    PROBELIGHT_TRY(shadows_->init(capabilities_));
    PROBELIGHT_TRY(track_->init());
    return lights_->init();
  }

  Status openButtonAndLed() {
    const AppSettings& settings = inputs_.settings;
    std::string error;
    button_ = makeButtonSource(options_.button, options_.key_path, settings.button.gpio, error);
    if (!button_) return Status::badInput(error);
    if (!button_->start(error)) {
      // A board without the GPIO chip (or a desktop) still runs the kiosk:
      // without a button, said once.
      if (options_.button != "gpio") return Status::badInput(error);
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
    return Status::ok();
  }

  // --- what the run leaves -----------------------------------------------------

  // DIR/camera.yaml and DIR/rig.yaml: what the frames in DIR were seen
  // through (--capture, --record).
  Status saveCalibration(const fs::path& dir, const char* flag) const {
    try {
      config::saveCameraFile((dir / "camera.yaml").string(), inputs_.camera);
      config::saveRigFile((dir / "rig.yaml").string(), inputs_.rig);
    } catch (const config::ConfigError& error) {
      return Status::runtimeFailure(std::string(error.what()) + " (" + flag + ")");
    }
    return Status::ok();
  }

  // --record DIR: made now, and refused when it already holds a recording
  // (written over, frame by frame, it would be lost).
  Status checkRecordingFolder() {
    if (options_.record_dir.empty()) return Status::ok();
    PROBELIGHT_TRY(createFolder(options_.record_dir, "--record"));
    std::error_code ec;
    if (fs::exists(fs::path(options_.record_dir) / kRecordingHeaderFile, ec) ||
        !listRecordedFrames(options_.record_dir).empty())
      return Status::badInput(options_.record_dir + ": already holds a recording (--record): record into a new folder");
    return Status::ok();
  }

  // Once the camera has started: what it is, and the calibration and rig
  // its frames are seen through, so that the recording replays alone.
  Status beginRecording() {
    if (options_.record_dir.empty()) return Status::ok();
    PROBELIGHT_TRY(saveCalibration(options_.record_dir, "--record"));
    RecordingHeader header;
    header.source = source_->name();
    header.stream = source_->streamDescription();
    header.exposure_control = source_->takesExposureLadders();
    header.shortest_exposure_us = source_->shortestExposureUs();
    header.simulation = simulation_;
    recorder_ = std::make_unique<FrameRecorder>(options_.record_dir);
    if (std::string error; !recorder_->begin(header, error)) return Status::runtimeFailure(error + " (--record)");
    return Status::ok();
  }

  // A recording that cannot be written (a full card) ends there, said once;
  // the kiosk goes on.
  void recordFrame(const FrameBuffer& frame) {
    if (!recorder_ || recorder_->stopped()) return;
    if (std::string error; !recorder_->record(frame, error))
      log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << error
           << " (--record): recording stopped; the kiosk goes on\n";
  }

  // The recording's section of the report, once its writes are done.
  void finishRecording(nlohmann::json& extra) {
    if (!recorder_) return;
    std::string error;
    const bool ok = recorder_->finish(error);
    nlohmann::json& section = extra["recording"];
    section = {{"dir", recorder_->dir()},
               {"frames_written", recorder_->framesWritten()},
               {"bytes_queued", recorder_->bytesRecorded()}};
    if (!ok) {
      section["error"] = error;
      if (!recorder_->stopped())  // not said yet: the failed write was among the last
        log_ << logPrefix(LogPriority::kWarning) << "probelight: warning: " << error << " (--record)\n";
    }
  }

  // --capture DIR: the last frame the pipeline ran on as the camera gave it
  // (frame.png), with the calibration and rig it was seen through, so that
  // `analyze` and `render` can be run on it.
  Status writeCapture() const {
    if (options_.capture_dir.empty() || last_pipeline_frame_.empty()) return Status::ok();
    const fs::path dir = options_.capture_dir;
    if (!writeRgbImage((dir / "frame.png").string(), last_pipeline_frame_))
      return Status::runtimeFailure("cannot write " + (dir / "frame.png").string() + " (--capture)");
    PROBELIGHT_TRY(saveCalibration(dir, "--capture"));
    if (!options_.quiet) log_ << "probelight: frame " << last_frame_number_ << " kept in " << dir.string() << "/\n";
    return Status::ok();
  }

  Status writeReport(double elapsed_s) {
    nlohmann::json& extra = report_.extra;
    extra["source"] = source_->name();
    finishRecording(extra);
    extra["display"] = display_->describe();
    extra["gl"] = capabilities_.summary();
    // Each stage's own sections; the camera's is shared by the link (losses,
    // exposures), the upload (its path) and the lights (the lock, the fit's
    // exposure).
    track_->writeReport(extra);
    maps_->writeReport(extra);
    lights_->writeReport(extra);
    shadows_->writeReport(extra);
    if (truth_) truth_->writeReport(extra);
    camera_->writeReport(extra["camera"]);
    upload_->writeReport(extra["camera"]);
    const nlohmann::json json = report_.toJson(static_cast<long long>(frames_done_), elapsed_s);
    const fs::path report_path = fs::path(options_.out_dir) / "report.json";
    std::ofstream out(report_path);
    out << json.dump(2) << "\n";
    if (!out) return Status::runtimeFailure("cannot write " + report_path.string());
    log_ << "probelight: " << frames_done_ << " frames in " << std::fixed << std::setprecision(1) << elapsed_s
         << " s; report: " << report_path.string() << "\n";
    return Status::ok();
  }

  std::uint64_t frameLimit() const { return static_cast<std::uint64_t>(options_.frames); }

  const RunOptions& options_;
  std::ostream& log_;
  LoadedInputs inputs_;
  RunReport report_;

  // The seams.
  // Only with --source sim, or a recording of it replayed: the truth.
  std::shared_ptr<const sim::World> world_;
  std::optional<RecordedSimulation> simulation_;  // world_'s settings, for --record
  std::unique_ptr<FrameSource> source_;
  std::unique_ptr<CameraLink> camera_;
  std::unique_ptr<Display> display_;  // owns the GL context: declared before the stages' GL objects
  gles::Capabilities capabilities_;
  std::unique_ptr<ButtonSource> button_;
  std::unique_ptr<StatusLed> status_led_;
  ServiceNotifier notifier_;

  // The stages, in the data path's order, and the observer.
  std::unique_ptr<UploadStage> upload_;
  std::unique_ptr<TrackStage> track_;
  std::unique_ptr<MapsStage> maps_;
  std::unique_ptr<LightsStage> lights_;
  std::unique_ptr<ShadowsStage> shadows_;
  std::unique_ptr<ResponseMatchStage> response_;
  std::unique_ptr<NoiseMatchStage> noise_;
  std::unique_ptr<BlurMatchStage> blur_;
  std::unique_ptr<MotionMatchStage> motion_;
  std::unique_ptr<LampExposureStage> lamp_exposure_;
  std::unique_ptr<ComposeStage> compose_;
  std::unique_ptr<TruthMonitor> truth_;

  std::uint64_t frames_done_ = 0;
  bool camera_frame_save_due_ = false;  // the display's save key: the next camera frame too
  bool quit_requested_ = false;  // the display's quit key (a window's Q or Esc, or its close)
  // How long a display's startupHint shows: long enough to read a line.
  static constexpr double kStartupHintSeconds = 6.0;
  double loop_start_s_ = 0.0;  // the frame loop's start (monotonicNowS): report.json's elapsed_s, resources.csv's
  ResourceLog resources_{0};  // output.resources_every_frames (setUp)
  HeapReleasePolicy heap_release_;
  tracking::TagTrackResult last_track_;  // redrawn over the last frame while it is kept
  std::uint64_t last_frame_number_ = 0;
  ImageRGB8 last_pipeline_frame_;  // --capture only
  std::unique_ptr<FrameRecorder> recorder_;  // --record only
  // The status the display's frame was last drawn with as a kept frame
  // (reset by every drawing): a kept frame with the same status is shown
  // again without drawing it.
  std::optional<std::string> kept_frame_status_;
  std::string last_logged_status_;
  std::string last_notified_status_;
};

}  // namespace

Status runKiosk(const RunOptions& options, std::ostream& log) { return Kiosk(options, log).run(); }

}  // namespace probelight
