#include "stages/lights_stage.hpp"

#include <cmath>
#include <iomanip>
#include <algorithm>
#include <numbers>
#include <ostream>
#include <sstream>

#include "core/log_priority.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/lighting_fit.hpp"
#include "stages/lighting_report.hpp"
#include "stages/stage_settings.hpp"

namespace probelight {

namespace {

std::string formatVector(const glm::dvec3& v) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "[" << v.x << ", " << v.y << ", " << v.z << "]";
  return out.str();
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

FrameExposure frameExposure(const FrameBuffer& frame) {
  return {frame.metadata.exposure_us, frame.metadata.analogue_gain};
}

// The ground's irradiance (E = pi D) in a diffuse map, facing up.
glm::dvec3 upwardIrradiance(const ibl::CubeMapRGB& diffuse) {
  return glm::dvec3(diffuse.sampleBilinear({0.0, 0.0, 1.0})) * std::numbers::pi;
}

BracketSettings bracketSettings(const LightsConfig& config) {
  return {config.bracket_step_stops, config.bracket_max_stops};
}

}  // namespace

LightsStage::LightsStage(const PipelineSettings& settings, const RigGeometry& rig, const CameraIntrinsics& camera,
                         ExposureControl& camera_control, RunReport& report, std::ostream& log)
    : settings_(settings),
      rig_(rig),
      camera_(camera),
      camera_control_(camera_control),
      report_(report),
      log_(log),
      machine_(settings.recalibration),
      bracket_(bracketSettings(settings.lights), camera_control, report),
      transition_(settings.lights.fade_s) {}

Status LightsStage::init() {
  try {
    bracket_tracker_ = std::make_unique<tracking::TagTracker>(tagDetectorSettings(settings_, rig_), rig_, camera_);
  } catch (const std::invalid_argument& bad_setting) {
    return Status::badInput(std::string("tracking: ") + bad_setting.what());
  }
  return Status::ok();
}

void LightsStage::warn(const std::string& message) const {
  log_ << logPrefix(LogPriority::kWarning) << "probelight: " << message << "\n";
}

// Events (a fit, a button press, the stored lighting), not per-frame
// lines: logged under --quiet too, so that the service's journal has them.
void LightsStage::info(const std::string& message) const {
  log_ << "probelight: " << message << "\n";
}

double LightsStage::clipLevel() const {
  return ibl::clippedMapLevel(ibl::HdrMergeSettings{settings_.maps.stages.camera_transfer}, rig_.probe_reflectance);
}

bool LightsStage::ballClips(const ImageRGB8& rgb, const ibl::ProbeOutline& outline) const {
  return ballPixelCodes(rgb, outline, ibl::HdrMergeSettings{settings_.maps.stages.camera_transfer}).clipped > 0;
}

// ---------------------------------------------------------------------------
// A frame arrives.

FrameAdmission LightsStage::admit(const FrameContext& ctx) {
  admitted_ = std::chrono::steady_clock::now();
  bracket_over_ = false;
  std::optional<ImageRGB8> rgb;  // made once, and only for a frame that becomes a rung
  const FrameArrival arrival = bracket_.arrive(frameExposure(ctx.frame), ctx.number, [&] {
    rgb = ctx.frame.toRgb();
    return ballClips(*rgb, bracket_frames_->outline);
  });
  switch (arrival.role) {
    case FrameRole::kPipeline:
      return {};
    case FrameRole::kSettling:
      return {false, "Recalibrating lights: exposure returning"};
    case FrameRole::kBracket:
      break;
  }
  bracket_over_ = arrival.bracket_over;
  if (arrival.keep_as_rung)
    bracket_frames_->frames.push_back(
        {"camera frame " + std::to_string(ctx.number), arrival.rung_ev, std::move(*rgb), ctx.time_s});
  if (arrival.not_delivered) {
    std::ostringstream message;
    message << "frame " << ctx.number << ": the camera did not deliver EV " << std::fixed << std::setprecision(1)
            << bracket_.pendingLadder()->ev.front() << " in " << BracketController::kMaxWaitFrames
            << " frames; the bracket ends with no frame";
    warn(message.str());
  }
  // One status for the whole bracket, so that the kept frame is drawn once.
  return {false, "Recalibrating lights: exposure bracket"};
}

Status LightsStage::afterKeptFrame(const FrameContext& ctx, MapsStage& maps) {
  if (!bracket_frames_) return Status::ok();  // settling after a bracket
  bracket_frames_->own_s += secondsSince(admitted_);
  if (!bracket_over_) return Status::ok();
  return finishBracket(ctx.number, maps);
}

Status LightsStage::finishPendingBracket(std::uint64_t frame_number, MapsStage& maps) {
  if (!bracket_.pending()) return Status::ok();
  return finishBracket(frame_number, maps);
}

// ---------------------------------------------------------------------------
// After the maps.

Status LightsStage::run(FrameContext& ctx, MapsStage& maps) {
  frame_time_s_ = ctx.time_s;
  if (ctx.maps_updated) {
    PROBELIGHT_TRY(followClippedLights(ctx.number, maps));
    PROBELIGHT_TRY(checkLightChange(ctx.number, maps));
  }
  showInMapsUnits(maps);
  // The state machine counts frames whose ball the maps hold.
  const FrameOutcome outcome = machine_.onFrame(ctx.maps_current);
  const bool ball_in_view = ctx.track.found && ctx.outline.valid;
  std::optional<ImageRGB8> rgb;
  auto frame_ball_clips = [&] {
    if (!rgb) rgb = ctx.frame.toRgb();
    return ballClips(*rgb, ctx.outline);
  };
  if (outcome == FrameOutcome::kNothing) {
    const RecalibrationProgress progress{recalibrating(), machine_.goodFramesSoFar(),
                                         machine_.policy().good_frames_needed};
    bracket_.leadTheLadder(frameExposure(ctx.frame), ctx.number, progress, ball_in_view, frame_ball_clips);
  }
  switch (outcome) {
    case FrameOutcome::kFitLights: {
      // With a bracket to take, the fit waits for its frames.
      if (ctx.track.found) {
        const BracketStart started =
            bracket_.start(frameExposure(ctx.frame), ctx.number, ctx.outline.valid, frame_ball_clips);
        if (started == BracketStart::kUnsupported && !said_no_exposure_control_) {
          // Every recalibration would find the same: say it once.
          said_no_exposure_control_ = true;
          warn("camera has no exposure control: no exposure bracket; the lights are fitted from single frames");
        }
        if (started == BracketStart::kStarted) {
          if (!rgb) rgb = ctx.frame.toRgb();
          bracket_frames_ = BracketFrames{std::move(*rgb), ctx.view, ctx.outline, exposure_locked_, {},
                                          std::chrono::steady_clock::now(), 0.0, ctx.time_s};
          bracket_frames_->response = frameResponseOf(ctx.frame.metadata);
          break;
        }
      }
      bracket_.fitWithoutBracket();
      FitFrame fit_frame;
      fit_frame.view = ctx.track.found ? &ctx.view : nullptr;
      fit_frame.read_pixel = [&frame = ctx.frame](int x, int y) { return frame.rgbAt(x, y); };
      fit_frame.exposure = {ctx.frame.metadata.exposure_us, ctx.frame.metadata.analogue_gain};
      fit_frame.response = frameResponseOf(ctx.frame.metadata);
      fit_frame.exposure_locked = exposure_locked_;
      PROBELIGHT_TRY(fitLights(ctx.number, fit_frame, maps));
      break;
    }
    case FrameOutcome::kCalibrationFailed: {
      bracket_.fitWithoutBracket();
      report_.count("calibrations_failed");
      std::ostringstream message;
      message << "frame " << ctx.number << ": recalibration gave up (ball not seen in " << machine_.policy().max_frames
              << " frames); previous lighting kept";
      warn(message.str());
      break;
    }
    case FrameOutcome::kNothing:
      break;
  }
  syncExposureLock(ctx.frames_since_camera_start);
  if (recalibrating()) {
    ctx.status = "Recalibrating lights (" + std::to_string(machine_.goodFramesSoFar()) + "/" +
                 std::to_string(machine_.policy().good_frames_needed) + ")" +
                 (ctx.status.empty() ? "" : ": " + ctx.status);
    report_.count("frames_recalibrating");
  }
  return Status::ok();
}

// ---------------------------------------------------------------------------
// The bracket and the fit.

// Merges what the bracket took (nothing usable: the fit goes on with the
// white border) and fits the lights from it.
Status LightsStage::finishBracket(std::uint64_t frame_number, MapsStage& maps) {
  const BracketRecord record = bracket_.finish();
  BracketFrames taken = std::move(*bracket_frames_);
  bracket_frames_.reset();
  const ibl::HdrMergeSettings merge{settings_.maps.stages.camera_transfer};
  // The camera took them in order: a frame too dark to show the tag was
  // taken right after the one before it.
  const BracketSetup setup{taken.view, taken.outline, rig_, tagDetectorSettings(settings_, rig_), merge,
                           maps.maps().reflection().face_size, true, bracket_tracker_.get(),
                           taken.reference_time_s};
  BracketMergeResult merged;
  const auto merge_started = std::chrono::steady_clock::now();
  {
    StageTimer timer(report_, kMergeStageName);
    merged = mergeBracketProbe(taken.reference, std::move(taken.frames), setup,
                               [&](const BracketCandidate& candidate, const std::string& why) {
                                 std::ostringstream message;
                                 message << "bracket: " << candidate.label << " (EV " << std::fixed
                                         << std::setprecision(1) << candidate.ev << ") left out: " << why;
                                 warn(message.str());
                               });
  }
  report_.count(merged.hdr_cube ? "brackets_merged" : "brackets_unusable");
  hdr_report_ = {{"method", merged.hdr_cube ? "bracket" : "none"},
                 {"status", merged.status},
                 {"frames", merged.frames},
                 {"still_clipped_sr", merged.still_clipped_sr},
                 {"camera_frames", frame_number - record.started_frame},
                 {"ladder_ev", record.ladder.ev},
                 {"ladder_asked_frames_before_fit", record.lead_frames},
                 {"exposure_latency_frames", record.latency_frames},
                 // From the fit frame to the merged map: the camera's frames plus the merge.
                 {"wall_ms", 1000.0 * secondsSince(taken.started)},
                 // Of that, probelight's own work: each bracket frame's checks and the kept
                 // frame drawn again, then the merge. The rest is waiting for the camera.
                 {"own_ms", 1000.0 * (taken.own_s + secondsSince(merge_started))}};
  FitFrame fit_frame;
  fit_frame.view = &taken.view;
  const ImageRGB8& reference = taken.reference;
  fit_frame.read_pixel = [&reference](int x, int y) {
    const std::uint8_t* p = reference.row(y) + 3 * x;
    return glm::u8vec3(p[0], p[1], p[2]);
  };
  fit_frame.exposure = record.base;
  // The bracket's merged map is in its base exposure's units; the white
  // balance was the reference frame's (AWB is locked with AE).
  fit_frame.response = taken.response;
  fit_frame.response.exposure_product =
      record.base.exposure_us > 0.0 ? exposureProduct(record.base.exposure_us, record.base.analogue_gain) : 0.0;
  if (merged.hdr_cube && maps.probe()) {
    // Into the probe, where earlier views' light joins it: the fit reads
    // the probe (fitLights).
    const double base = record.base.exposure_us > 0.0
                            ? exposureProduct(record.base.exposure_us, record.base.analogue_gain)
                            : 0.0;
    PROBELIGHT_TRY(maps.mergeBracket(taken.view, *merged.hdr_cube, merged.still_clipped, base));
  } else {
    fit_frame.hdr = std::move(merged.hdr_cube);
  }
  fit_frame.exposure_locked = taken.exposure_locked;
  return fitLights(frame_number, fit_frame, maps);
}

Status LightsStage::fitLights(std::uint64_t frame_number, const FitFrame& fit_frame, MapsStage& maps) {
  std::string error;
  std::vector<float> validity;
  const std::optional<ibl::CubeMapRGB> reflection = maps.maps().readReflection(error, &validity);
  if (!reflection) return Status::runtimeFailure(error);
  // A probe over views that holds measured light above the 8-bit range (a
  // bracket's, this one's or an earlier one's where no later view saw it
  // change) is the fit's HDR map: the same texels as the maps, unclamped.
  std::optional<ibl::CubeMapRGB> probe_hdr;
  if (!fit_frame.hdr && maps.probe() && maps.probe()->holdsAboveClip()) probe_hdr = maps.probe()->hdrMap();
  const ibl::CubeMapRGB* hdr_map = fit_frame.hdr ? &*fit_frame.hdr : probe_hdr ? &*probe_hdr : nullptr;
  const LightsConfig& config = settings_.lights;
  ibl::LightingFit fit;
  {
    StageTimer timer(report_, kFitStageName);
    ibl::LightingFitInputs inputs;
    inputs.map_8bit = &*reflection;
    inputs.validity = &validity;
    inputs.hdr_map = hdr_map;
    inputs.view = fit_frame.view;
    inputs.read_pixel = fit_frame.read_pixel;
    inputs.rig = rig_;
    // The border is read only where the fit may use it.
    if (config.white_reference && !inputs.hdr_map) inputs.white_ring = tagWhiteRingOf(rig_);
    fit = ibl::fitLighting(inputs, lightingFitSettings(settings_));
  }
  if (fit.method == ibl::LightingFitMethod::kBracket)
    hdr_report_["clipped_lights"] = clippedLightsJson<nlohmann::json>(fit.clipped_lights);
  reportWhiteBorder(fit);
  for (const std::string& warning : fit.warnings) warn(warning);
  // The clipped lights follow the frame-rate maps from now on: how much of
  // each still clips in them, against how much did in the map they were
  // found beside.
  clipped_.follow(fit.clipped_lights, *reflection, clipLevel(),
                  exposureProduct(fit_frame.exposure.exposure_us, fit_frame.exposure.analogue_gain));
  ibl::setClippedLights(lighting_, clipped_.lights());
  transition_.retarget(fit.dome, frame_time_s_);
  // What checkLightChange compares with later: the same estimate, from the
  // same map.
  if (const std::optional<ibl::CubeMapRGB> diffuse = maps.maps().readDiffuse(error)) {
    lights_fitted_e_up_ = upwardIrradiance(*diffuse);
    e_up_response_ = maps.mapsResponse();
  }
  lighting_.highlight_direction_w = glm::vec3(fit.dominant.direction_w);
  lighting_.highlight_rgb = glm::vec3(fit.dominant.rgb);
  fit_response_ = fit_frame.response;
  showInMapsUnits(maps);
  report_.count("calibrations_completed");
  // The ball's brightness in the fit follows these (0: the source cannot say).
  exposure_at_last_fit_ = {{"frame", frame_number},
                           {"exposure_us", fit_frame.exposure.exposure_us},
                           {"analogue_gain", fit_frame.exposure.analogue_gain},
                           {"locked", fit_frame.exposure_locked}};
  saveLighting(fit, maps);
  lights_report_ = {{"frame", frame_number},
                    {"placement", ibl::toString(config.dome.placement)},
                    {"lights", domeLightsJson<nlohmann::json>(fit.dome)},
                    {"dominant_light", dominantLightJson<nlohmann::json>(fit.dominant)}};
  info("frame " + std::to_string(frame_number) + ": lights recalibrated (" + std::to_string(fit.dome.size()) + ", " +
       ibl::toString(config.dome.placement) + "), dominant light toward " + formatVector(fit.dominant.direction_w) +
       " rgb " + formatVector(fit.dominant.rgb));
  return Status::ok();
}

// lights.white_reference: what the tag's white border in the fit's frame
// said and did, and the ball's post beside it (lights.post_reference).
void LightsStage::reportWhiteBorder(const ibl::LightingFit& fit) {
  if (!fit.border || !fit.border_correction) return;
  const bool used = fit.method == ibl::LightingFitMethod::kWhiteBorder ||
                    fit.method == ibl::LightingFitMethod::kWhiteBorderAndPost;
  if (fit.post) report_.count(std::string("post_") + ibl::toString(fit.post->reading.status));
  report_.count(std::string("white_border_") + ibl::toString(fit.border_correction->status));
  white_border_report_ = whiteBorderReportJson(*fit.border, *fit.border_correction,
                                               used ? fit.clipped_lights : std::vector<ibl::ClippedLight>{});
  if (fit.post) white_border_report_["post"] = postCorrectionJson<nlohmann::json>(*fit.post, rig_);
}

// Kept for the next start; a failed write leaves the old file whole.
void LightsStage::saveLighting(const ibl::LightingFit& fit, MapsStage& maps) {
  if (settings_.state.dir.empty()) return;
  std::string error;
  const StoredLighting stored{fit.dome,           fit.dominant,           ibl::toString(settings_.lights.dome.placement),
                              clipped_.lights(), clipped_.shareAtFit(), clipped_.exposureAtFit()};
  if (probelight::saveLighting(settings_.state.dir, stored, error))
    report_.count("state_saves");
  else
    warn("warning: lighting not saved: " + error);
  // And the probe the fit was made from, so that a restart starts from
  // every view seen so far.
  if (!maps.probe()) return;
  if (maps.saveProbe(settings_.state.dir, error))
    report_.count("probe_saves");
  else
    warn("warning: probe not saved: " + error);
}

// After each map update: each clipped light scaled by how much of it still
// clips and by the exposure (stages/clipped_light_follower.hpp). One
// read-back of the reflection map per map update, none when there are no
// clipped lights.
Status LightsStage::followClippedLights(std::uint64_t frame_number, const MapsStage& maps) {
  if (clipped_.empty()) return Status::ok();
  std::vector<double> shares;
  const glm::dvec3 fit_to_maps = responseRatio(fit_response_, maps.mapsResponse());
  {
    StageTimer timer(report_, kRescaleStageName);
    std::string error;
    std::optional<ibl::CubeMapRGB> live = maps.maps().readReflection(error);
    if (!live) return Status::runtimeFailure(error);
    // Compared with the clip in the fit frame's units: the probe's map is
    // clipped there (MapsStage::setLightsFittedAt), and a light still as
    // bright as the clip was then still clips, whatever auto exposure did.
    const glm::vec3 to_fit(1.0 / fit_to_maps);
    for (auto& face : live->faces)
      for (glm::vec3& texel : face) texel *= to_fit;
    // With the probe over views, the texels a sharper view showed the fit's
    // bracket had smeared a light over are no longer the light's.
    const std::vector<std::uint8_t> resolved =
        maps.probe() ? maps.probe()->texelsResolvedBySharperViews() : std::vector<std::uint8_t>{};
    shares = clipped_.sharesFor(*live, clipLevel(), maps.probe() ? &resolved : nullptr);
  }
  // In the fit's units, as the rest of lighting_: showInMapsUnits brings
  // them into the maps' (the exposure now over the exposure at the fit,
  // and the white balance's gains).
  ibl::setClippedLights(lighting_, clipped_.lights(), shares);
  report_.count("clipped_rescales");
  std::vector<double> scale = shares;
  for (double& s : scale) s *= fit_to_maps.g;
  clipped_now_report_ = {{"frame", frame_number}, {"scale", scale}, {"still_clipping_share", shares}};
  return Status::ok();
}

void LightsStage::showInMapsUnits(const MapsStage& maps) {
  const glm::vec3 factor(responseRatio(fit_response_, maps.mapsResponse()));
  shown_lighting_ = lighting_;
  shown_lighting_.ambient_rgb *= factor;
  shown_lighting_.highlight_rgb *= factor;
  for (glm::vec3& rgb : shown_lighting_.clipped_diffuse_rgb) rgb *= factor;
  shown_lighting_.dome_rgb_scale = factor;
  // The room's light on the ground as fitted, in the maps' units: the
  // diffuse map's upward irradiance and the clipped lights' (which the
  // 8-bit map lacks), E = pi (D(+z) + sum C_k max(0, l_k . z)).
  room_e_up_maps_.reset();
  if (ibl::luminance(lights_fitted_e_up_) > 0.0) {
    glm::dvec3 room = lights_fitted_e_up_ * responseRatio(e_up_response_, maps.mapsResponse());
    for (int k = 0; k < ibl::SceneLighting::kMaxClippedLights; ++k)
      room += std::numbers::pi * glm::dvec3(shown_lighting_.clipped_diffuse_rgb[static_cast<size_t>(k)]) *
              std::max(0.0, static_cast<double>(shown_lighting_.clipped_direction_w[static_cast<size_t>(k)].z));
    room_e_up_maps_ = room;
  }
}

// lights.refit_when_light_changes: at each map update (the policy already
// keeps those to when the ball's image changed, or every max_age_frames),
// the ground's irradiance in the diffuse map against the one the lights
// were fitted to; a large change (a lamp switched on or off) starts a
// recalibration. The read-back is 6 faces of 16^2.
Status LightsStage::checkLightChange(std::uint64_t frame_number, const MapsStage& maps) {
  const LightsConfig& config = settings_.lights;
  if (!config.refit_when_light_changes || machine_.state() != AppState::kRunning || transition_.empty())
    return Status::ok();
  std::string error;
  const std::optional<ibl::CubeMapRGB> diffuse = maps.maps().readDiffuse(error);
  if (!diffuse) return Status::runtimeFailure(error);
  // Both in the units of the maps the fit read (an exposure or white
  // balance change is not a change of the light).
  const double before = ibl::luminance(lights_fitted_e_up_);
  const double now =
      ibl::luminance(upwardIrradiance(*diffuse) * responseRatio(maps.mapsResponse(), e_up_response_));
  if (before > 0.0 && std::abs(now - before) > config.refit_change_fraction * before) {
    report_.count("refits_for_light_change");
    std::ostringstream message;
    message << "frame " << frame_number << ": the light changed by " << std::fixed << std::setprecision(0)
            << 100.0 * (now - before) / before << "%: recalibrating";
    info(message.str());
    machine_.onButtonPress();
  }
  return Status::ok();
}

// AE/AWB frozen while the lights are fitted (not in the first frames after
// the camera starts, while AE still converges).
void LightsStage::syncExposureLock(std::uint64_t frames_since_camera_start) {
  const CameraConfig& config = settings_.camera;
  const bool want = config.lock_exposure && recalibrating() &&
                    frames_since_camera_start > static_cast<std::uint64_t>(config.exposure_settle_frames);
  if (want == exposure_locked_) return;
  if (!camera_control_.lockExposure(want)) return;  // no such controls: nothing to say
  exposure_locked_ = want;
  report_.count(want ? "exposure_locks" : "exposure_unlocks");
}

// ---------------------------------------------------------------------------
// The button and the camera.

bool LightsStage::onButtonPress() {
  // A bracket still being taken is part of the recalibration before it.
  const bool was_running = machine_.state() == AppState::kRunning && !bracket_.pending();
  if (was_running) machine_.onButtonPress();
  report_.count(was_running ? "button_presses_accepted" : "button_presses_ignored");
  info(std::string("button: ") + (was_running ? "recalibrating lights" : "already recalibrating, ignored"));
  return was_running;
}

void LightsStage::onLongPress() {
  if (stored_lighting_ && machine_.state() == AppState::kRunning && !bracket_.pending()) {
    showStoredLighting(frame_time_s_);
    report_.count("button_long_presses_restored");
    info("button: long press: back to the stored lighting");
    return;
  }
  report_.count("button_long_presses_ignored");
  info(std::string("button: long press ignored (") + (stored_lighting_ ? "recalibrating" : "no stored lighting") + ")");
}

void LightsStage::onCameraLost() {
  exposure_locked_ = false;  // a new stream starts with AE running
  bracket_.onCameraLost();
}

// ---------------------------------------------------------------------------
// The stored lighting.

void LightsStage::loadStoredLighting() {
  const std::string& dir = settings_.state.dir;
  state_report_ = {{"dir", dir}, {"loaded", false}};
  if (dir.empty()) return;
  std::string error;
  stored_lighting_ = loadLighting(dir, error);
  if (stored_lighting_) {
    showStoredLighting(0.0);
    state_report_["loaded"] = true;
    info("lighting from " + lightingStatePath(dir).string() + " (" + std::to_string(stored_lighting_->lights.size()) +
         " lights)");
  } else if (!error.empty()) {
    state_report_["error"] = error;
    warn("warning: " + error + "; starting without stored lighting");
  }
}

void LightsStage::showStoredLighting(double now_s) {
  transition_.retarget(stored_lighting_->lights, now_s);
  // And the fit's clipped lights, followed from the next map update on.
  clipped_.restore(stored_lighting_->clipped_lights, stored_lighting_->clipped_share_at_fit,
                   stored_lighting_->exposure_at_fit);
  ibl::setClippedLights(lighting_, clipped_.lights());
  lighting_.highlight_direction_w = glm::vec3(stored_lighting_->dominant.direction_w);
  lighting_.highlight_rgb = glm::vec3(stored_lighting_->dominant.rgb);
  // The stored exposure (the white balance is not kept: taken as today's).
  // exposureProduct's 1 stands for a source that could not say.
  const double stored_exposure = stored_lighting_->exposure_at_fit;
  fit_response_ = FrameResponse{stored_exposure > 1.0 ? stored_exposure : 0.0, 0.0, 0.0};
  shown_lighting_ = lighting_;  // brought into the maps' units from their next update
}

void LightsStage::writeReport(nlohmann::json& report) const {
  report["state"] = state_report_;
  report["state_at_end"] = toString(machine_.state());
  if (!lights_report_.is_null()) report["lights"] = lights_report_;
  if (!hdr_report_.is_null()) report["hdr"] = hdr_report_;
  if (!white_border_report_.is_null()) report["white_border"] = white_border_report_;
  if (!clipped_now_report_.is_null()) report["clipped_lights_now"] = clipped_now_report_;
  report["camera"]["exposure_locks"] = report_.counter("exposure_locks");
  report["camera"]["exposure_at_last_fit"] = exposure_at_last_fit_;
}

}  // namespace probelight
