#include "stages/maps_stage.hpp"

#include <algorithm>
#include <vector>

#include "ibl/glossy_maps.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "stages/clipped_light_follower.hpp"
#include "stages/gpu_stage_timer.hpp"
#include "stages/stage_settings.hpp"
#include "stages/state_store.hpp"

namespace probelight {

namespace {

// The status bar's words for a ball the maps cannot use (the rest say nothing).
const char* statusFor(MapSkipReason skip) {
  switch (skip) {
    case MapSkipReason::kBallNotInView: return "Mirror ball not fully in view: lighting kept";
    case MapSkipReason::kBallTooSmall: return "Mirror ball too small in the image: lighting kept";
    case MapSkipReason::kBallSaturated: return "Mirror ball image all white (overexposed?): lighting kept";
    case MapSkipReason::kBallDark: return "Mirror ball image all black (covered?): lighting kept";
    default: return nullptr;
  }
}

// The largest channel value of a map (what the object can reflect at most).
double largestChannel(const ibl::CubeMapRGB& map) {
  float peak = 0.0f;
  for (const auto& face : map.faces)
    for (const glm::vec3& texel : face) peak = std::max({peak, texel.r, texel.g, texel.b});
  return peak;
}

}  // namespace

MapsStage::MapsStage(const PipelineSettings& settings, const RigGeometry& rig, bool object_reads_glossy,
                     bool merge_views, RunReport& report)
    : settings_(settings),
      probe_reflectance_(rig.probe_reflectance),
      object_reads_glossy_(object_reads_glossy),
      report_(report),
      policy_(settings.map_updates) {
  if (merge_views)
    probe_.emplace(settings.maps.stages.camera_transfer, rig, settings.maps.stages.reflection_face_size);
}

Status MapsStage::init(const gles::Capabilities& capabilities) {
  std::string error;
  if (!maps_.init(capabilities, environmentMapSettings(settings_, object_reads_glossy_), error))
    return Status::runtimeFailure("GPU set-up failed: " + error);
  return Status::ok();
}

const char* MapsStage::diffuseStageName() const {
  return settings_.maps.diffuse_method == DiffuseMethod::kSH9 ? "diffuse_sh9" : "diffuse_blur";
}

Status MapsStage::run(FrameContext& ctx, const passes::CameraFrameTexture& frame) {
  MapFrameInput input;
  input.tag_found = ctx.track.found;
  input.outline = ctx.outline;
  input.rotation_cam_from_world = ctx.track.pose.R_cam_from_world;
  input.luma = ctx.frame.luma();
  ctx.map_decision = policy_.decide(input);
  const MapUpdateDecision& decision = ctx.map_decision;
  record(decision);
  if (const char* status = statusFor(decision.skip)) ctx.status = status;
  if (decision.update) {
    PROBELIGHT_TRY(remake(ctx.view, frame, ctx.frame, decision.new_weight));
    maps_view_ = ctx.view;
    maps_response_ = frameResponseOf(ctx.frame.metadata);
    ctx.maps_updated = true;
  } else {
    report_.recordStageSkip(kReflectionStageName, toString(decision.skip));
    report_.recordStageSkip(diffuseStageName(), toString(decision.skip));
  }
  // Counted toward a recalibration: maps that hold this frame's ball.
  ctx.maps_current = decision.update || decision.skip == MapSkipReason::kImageUnchanged;
  return Status::ok();
}

void MapsStage::skip(const std::string& reason) {
  report_.recordStageSkip(kReflectionStageName, reason);
  report_.recordStageSkip(diffuseStageName(), reason);
  ++skip_reasons_[reason];
}

Status MapsStage::remake(const ibl::MirrorBallView& view, const passes::CameraFrameTexture& frame,
                         const FrameBuffer& pixels, float new_weight) {
  std::string error;
  // A blended diffuse update mixes the last maps with this frame's: in
  // this frame's units (1 while the camera says nothing or nothing moved).
  maps_.setPreviousDiffuseUnits(glm::vec3(responseRatio(maps_response_, frameResponseOf(pixels.metadata))));
  const bool finish_gpu = settings_.gpu_finish;
  {
    GpuStageTimer timer(report_, kReflectionStageName, finish_gpu);
    if (!maps_.updateReflection(frame, view, probe_reflectance_, error)) return Status::runtimeFailure(error);
  }
  // The frame's 8-bit white through the ball (until the probe says more exactly).
  reflection_peak_ = 1.0 / probe_reflectance_;
  if (!probe_) return remakeFromReflection(new_weight);
  bool diffuse_due = true, glossy_due = true;
  PROBELIGHT_TRY(mergeIntoProbe(view, pixels, diffuse_due, glossy_due));
  static const std::string kUnchanged = "probe unchanged";
  if (!have_maps_) diffuse_due = glossy_due = true;
  if (!diffuse_due) report_.recordStageSkip(diffuseStageName(), kUnchanged);
  if (!glossy_due && object_reads_glossy_) report_.recordStageSkip(kGlossyStageName, kUnchanged);
  // The probe is its own temporal filter: its maps are not blended again.
  return remakeFromReflection(1.0f, diffuse_due, glossy_due);
}

Status MapsStage::mergeIntoProbe(const ibl::MirrorBallView& view, const FrameBuffer& pixels, bool& diffuse_due,
                                 bool& glossy_due) {
  StageTimer timer(report_, kMergeStageName);
  std::string error;
  std::vector<float> validity;
  const std::optional<ibl::CubeMapRGB> map = maps_.readReflection(error, &validity);
  if (!map) return Status::runtimeFailure(error);
  // The probe follows the camera's exposure, so that its maps are in this
  // frame's units as a single view's are (a source that cannot say leaves
  // it as it is).
  if (pixels.metadata.exposure_us > 0.0)
    probe_->followExposure(exposureProduct(pixels.metadata.exposure_us, pixels.metadata.analogue_gain));
  probe_->followWhiteBalance(pixels.metadata.red_gain, pixels.metadata.blue_gain);
  maps_response_ = frameResponseOf(pixels.metadata);
  const ProbeViewCounts counts = probe_->addView(view, *map, &validity, nullptr, 1.0, &pixels);
  ++probe_views_;
  probe_frame_texels_ += counts.texels_from_frame_around_ball;
  probe_totals_.seen += counts.merge.seen;
  probe_totals_.first += counts.merge.first;
  probe_totals_.merged += counts.merge.merged;
  probe_totals_.changed += counts.merge.changed;
  probe_totals_.raised += counts.merge.raised;
  probe_totals_.kept += counts.merge.kept;
  // The diffuse map is remade once the probe's irradiance at some axis
  // normal has moved by a quarter of a display code since the diffuse map
  // was made from it: an 8-bit sRGB code step is about 2.4 / code relative
  // (1% at code 240), and a change at any normal shows at least 1 / sqrt(3)
  // of itself at the nearest axis, so 0.25% there keeps every normal below
  // half a step. Small moves add up until they matter.
  const std::array<double, 6> now = probe_->axisIrradiance();
  diffuse_due = false;
  for (int axis = 0; axis < 6; ++axis) {
    const double at = axis_irradiance_at_diffuse_[axis];
    if (!(std::abs(now[axis] - at) <= kInvisibleIrradianceChange * at)) diffuse_due = true;
  }
  // The glossy lobes are narrower: any texel moved by a noise sigma, or
  // the diffuse map remade, remakes them.
  glossy_due = object_reads_glossy_ && (diffuse_due || counts.merge.largest_move_sigmas >= 1.0);
  if (!diffuse_due && !glossy_due) ++probe_views_unchanged_;
  return showProbe();
}

Status MapsStage::showProbe() {
  std::string error;
  const std::vector<float> validity = probe_->validity();
  // The fit frame's clip level in the maps' units (1 while recalibrating:
  // the fit reads the map as the 8-bit frames show it).
  const glm::dvec3 clip_scale =
      lights_fitted_at_ ? responseRatio(*lights_fitted_at_, maps_response_) : glm::dvec3(1.0);
  const ibl::CubeMapRGB live = probe_->liveMap(glm::vec3(clip_scale));
  if (!maps_.setReflection(live, error, &validity)) return Status::runtimeFailure(error);
  reflection_peak_ = largestChannel(live);
  return Status::ok();
}

Status MapsStage::mergeBracket(const ibl::MirrorBallView& view, const ibl::CubeMapRGB& hdr,
                               const std::vector<std::uint8_t>& still_clipped, double exposure_product) {
  if (!probe_) return Status::ok();
  // On a frame the maps stage already counted (a bracket's): its time is
  // the merge's, the diffuse and glossy passes included, so that each stage
  // still counts every frame once.
  StageTimer timer(report_, kMergeStageName);
  probe_->addView(view, hdr, nullptr, &still_clipped, probe_->toProbeExposure(exposure_product), nullptr);
  ++probe_brackets_;
  PROBELIGHT_TRY(showProbe());
  return remakeFromReflection(1.0f, true, true, false);
}

bool MapsStage::saveProbe(const std::string& state_dir, std::string& error) {
  if (!probe_ || probe_->empty()) return true;
  const StoredProbe stored{probe_->accumulator().faceSize(), probe_->exposure(), probe_->accumulator().texels()};
  return probelight::saveProbe(state_dir, stored, error);
}

std::string MapsStage::loadStoredProbe(const std::string& state_dir) {
  if (!probe_ || state_dir.empty()) return "";
  std::string error;
  const std::optional<StoredProbe> stored = loadProbe(state_dir, error);
  probe_report_["loaded"] = false;
  if (!stored) {
    if (!error.empty()) probe_report_["error"] = error;
    return error;
  }
  if (!probe_->restore(stored->texels, stored->exposure_product, error)) {
    error = probeStatePath(state_dir).string() + ": field 'face_size': " + error +
            " (environment_maps.face_size changed)";
    probe_report_["error"] = error;
    return error;
  }
  probe_report_["loaded"] = true;
  return "";
}

Status MapsStage::setProbe(const ibl::CubeMapRGB& map, const std::vector<float>& validity) {
  std::string error;
  {
    GpuStageTimer timer(report_, kReflectionStageName, settings_.gpu_finish);
    if (!maps_.setReflection(map, error, &validity)) return Status::runtimeFailure(error);
  }
  reflection_peak_ = largestChannel(map);
  return remakeFromReflection(1.0f);
}

Status MapsStage::remakeFromReflection(float new_weight, bool diffuse, bool glossy, bool timed) {
  std::string error;
  const bool finish_gpu = settings_.gpu_finish;
  // Temporal smoothing in both methods: diffuse = w * new + (1 - w) * previous.
  if (diffuse) {
    if (probe_) axis_irradiance_at_diffuse_ = probe_->axisIrradiance();
    std::optional<GpuStageTimer> timer;
    if (timed) timer.emplace(report_, diffuseStageName(), finish_gpu);
    if (settings_.maps.diffuse_method == DiffuseMethod::kSH9) {
      std::vector<float> validity;
      const std::optional<ibl::CubeMapRGB> reflection = maps_.readReflection(error, &validity);
      if (!reflection || !maps_.updateDiffuseFromSH9(ibl::projectToSH9(*reflection, &validity), error, new_weight))
        return Status::runtimeFailure(error);
    } else if (!maps_.updateDiffuse(error, new_weight)) {
      return Status::runtimeFailure(error);
    }
  }
  // Glossy levels only when the object's material sits between them (a
  // mirror or a matte object never reads them).
  if (object_reads_glossy_ && glossy) {
    std::optional<GpuStageTimer> timer;
    if (timed) timer.emplace(report_, kGlossyStageName, finish_gpu);
    if (!maps_.updateGlossy(error)) return Status::runtimeFailure(error);
  }
  have_maps_ = true;
  return Status::ok();
}

void MapsStage::record(const MapUpdateDecision& decision) {
  if (decision.update)
    ++update_causes_[toString(decision.cause)];
  else
    ++skip_reasons_[toString(decision.skip)];
  if (decision.center_shift_px) center_shift_px_.add(*decision.center_shift_px);
  if (decision.radius_change_px) radius_change_px_.add(*decision.radius_change_px);
  if (decision.rotation_change_deg) rotation_change_deg_.add(*decision.rotation_change_deg);
  if (decision.image_change_code) image_change_code_.add(*decision.image_change_code);
}

void MapsStage::writeReport(nlohmann::json& report) const {
  report["map_storage"] = maps_.storageDescription();
  if (probe_) {
    nlohmann::json& probe = report["probe_merge"];
    probe = probe_report_.is_null() ? nlohmann::json::object() : probe_report_;
    probe["views"] = probe_views_;
    probe["views_remaking_nothing"] = probe_views_unchanged_;
    probe["brackets"] = probe_brackets_;
    probe["texels_seen"] = probe_totals_.seen;
    probe["texels_first_seen"] = probe_totals_.first;
    probe["texels_merged"] = probe_totals_.merged;
    probe["texels_changed"] = probe_totals_.changed;
    probe["texels_raised_by_clipped"] = probe_totals_.raised;
    probe["texels_clipped_kept"] = probe_totals_.kept;
    probe["texels_from_frame_around_ball"] = probe_frame_texels_;
    probe["seen_sphere_fraction"] = probe_->accumulator().seenSolidAngleFraction();
    probe["exposure"] = probe_->exposure();
  }
  nlohmann::json& out = report["map_updates"];
  long long updated = 0;
  long long skipped = 0;
  for (const auto& [cause, n] : update_causes_) updated += n;
  for (const auto& [reason, n] : skip_reasons_) skipped += n;
  out["updated"] = updated;
  out["update_causes"] = update_causes_;
  out["skipped"] = skipped;
  out["skip_reasons"] = skip_reasons_;
  out["smoothing_new_weight"] = policy_.settings().smoothing_new_weight;
  // What the policy measured between consecutive frames (and against the
  // maps' reference), to see its thresholds' margins on a real run.
  nlohmann::json& measured = out["measured"];
  measured = nlohmann::json::object();
  recordSeries(measured, "center_shift_px", center_shift_px_);
  recordSeries(measured, "radius_change_px", radius_change_px_);
  recordSeries(measured, "rotation_change_deg", rotation_change_deg_);
  recordSeries(measured, "image_change_code", image_change_code_);
}

}  // namespace probelight
