#include "stages/maps_stage.hpp"

#include <vector>

#include "ibl/glossy_maps.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "stages/gpu_stage_timer.hpp"
#include "stages/stage_settings.hpp"

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

}  // namespace

MapsStage::MapsStage(const PipelineSettings& settings, double probe_reflectance, bool object_reads_glossy,
                     RunReport& report)
    : settings_(settings),
      probe_reflectance_(probe_reflectance),
      object_reads_glossy_(object_reads_glossy),
      report_(report),
      policy_(settings.map_updates) {}

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
    PROBELIGHT_TRY(remake(ctx.view, frame, decision.new_weight));
    maps_view_ = ctx.view;
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

Status MapsStage::remake(const ibl::MirrorBallView& view, const passes::CameraFrameTexture& frame, float new_weight) {
  std::string error;
  const bool finish_gpu = settings_.gpu_finish;
  {
    GpuStageTimer timer(report_, kReflectionStageName, finish_gpu);
    if (!maps_.updateReflection(frame, view, probe_reflectance_, error)) return Status::runtimeFailure(error);
  }
  return remakeFromReflection(new_weight);
}

Status MapsStage::setProbe(const ibl::CubeMapRGB& map, const std::vector<float>& validity) {
  std::string error;
  {
    GpuStageTimer timer(report_, kReflectionStageName, settings_.gpu_finish);
    if (!maps_.setReflection(map, error, &validity)) return Status::runtimeFailure(error);
  }
  return remakeFromReflection(1.0f);
}

Status MapsStage::remakeFromReflection(float new_weight) {
  std::string error;
  const bool finish_gpu = settings_.gpu_finish;
  // Temporal smoothing in both methods: diffuse = w * new + (1 - w) * previous.
  {
    GpuStageTimer timer(report_, diffuseStageName(), finish_gpu);
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
  if (object_reads_glossy_) {
    GpuStageTimer timer(report_, kGlossyStageName, finish_gpu);
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
