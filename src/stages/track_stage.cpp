#include "stages/track_stage.hpp"

#include <stdexcept>

#include "stages/stage_settings.hpp"
#include "tracking/probe_edge_fit.hpp"

namespace probelight {

TrackStage::TrackStage(const PipelineSettings& settings, const RigGeometry& rig, const CameraIntrinsics& camera,
                       RunReport& report, bool fit_probe_edges)
    : settings_(settings), rig_(rig), camera_(camera), report_(report), fit_probe_edges_(fit_probe_edges) {}

Status TrackStage::init() {
  try {
    tracker_ = std::make_unique<tracking::TagTracker>(tagDetectorSettings(settings_, rig_), rig_, camera_);
    smoother_ = std::make_unique<tracking::PoseSmoother>(settings_.tracking.smoothing, camera_,
                                                         tracking::smoothingReferencePoints(rig_));
  } catch (const std::invalid_argument& bad_setting) {
    return Status::badInput(std::string("tracking: ") + bad_setting.what());
  }
  return Status::ok();
}

void TrackStage::run(FrameContext& ctx) {
  {
    StageTimer timer(report_, kStageName);
    // The Y' plane of a camera frame in place, or the luma the source made.
    const LumaView luma = ctx.frame.luma();
    ctx.track = tracker_->track(luma.data, luma.width, luma.height, luma.stride);
  }
  // The rig's ball, as corrected by probe_refinement (nothing when it is off).
  const glm::dvec3 probe_center_w = rig_.probe_center_w + probe_center_offset_w_;
  const double probe_radius_m = rig_.probe_radius_m * probe_radius_scale_;
  // Everything downstream (ball crop, maps, object) uses the smoothed pose.
  if (ctx.track.found && settings_.tracking.smoothing.enabled) {
    ctx.unsmoothed_view = ibl::MirrorBallView{camera_, ctx.track.pose, probe_center_w, probe_radius_m};
    ctx.track.pose = smoother_->update(ctx.track.pose, ctx.time_s);
  }
  ctx.view = ibl::MirrorBallView{camera_, ctx.track.pose, probe_center_w, probe_radius_m};
  tag_status_frames_[tracking::toString(ctx.track.status_code)] += 1;
  if (ctx.track.refinement_reused) ++refinement_reused_frames_;
  if (!ctx.track.found) {
    report_.count("frames_without_tag");
    ctx.status = (ctx.track.status_code == tracking::TagTrackStatus::kNoTag ? "No tag in view: " : "Tag not usable: ") +
                 ctx.track.status;
    last_tag_problem_ = {{"frame", ctx.number},
                         {"status", tracking::toString(ctx.track.status_code)},
                         {"message", ctx.track.status}};
    return;
  }
  ctx.outline = ibl::computeProbeOutline(ctx.view);
  refineProbe(ctx);
}

void TrackStage::skip(const std::string& reason) {
  report_.recordStageSkip(kStageName, reason);
  tag_status_frames_[reason] += 1;  // not looked for
}

void TrackStage::reset() {
  tracker_->resetHistory();
  smoother_->reset();
  probe_center_offset_w_ = glm::dvec3(0.0);
  probe_radius_scale_ = 1.0;
}

// Fits this frame's ball outline to the image and moves the rig correction
// toward what the fit implies (tracking/probe_edge_fit.hpp). Refines only on
// a ball fully in view and big enough to be worth a map; the correction
// applies from the next frame on.
void TrackStage::refineProbe(FrameContext& ctx) {
  const ProbeRefinementConfig& config = settings_.probe_refinement;
  const ibl::ProbeOutline& outline = ctx.outline;
  if (!outline.valid || !outline.fully_in_image) return;
  const bool refine = config.enabled && outline.radius_px >= settings_.map_updates.min_probe_radius_px;
  if (!refine && !fit_probe_edges_) return;
  std::optional<StageTimer> timer;
  if (refine) timer.emplace(report_, kRefineStageName);
  const LumaView luma = ctx.frame.luma();
  ctx.probe_edge_fit = tracking::fitProbeOutlineToEdges(luma.data, luma.width, luma.height, luma.stride, outline,
                                                        rig_.probe_reflectance,
                                                        settings_.maps.stages.camera_transfer);
  if (!refine) return;
  const tracking::ProbeEdgeFit& fit = *ctx.probe_edge_fit;
  if (!fit.ok) {
    ++probe_fits_refused_;
    probe_fit_last_refusal_ = fit.reason;
    return;
  }
  ++probe_fits_;
  probe_fit_shift_px_.add(glm::length(fit.shift_px));
  const ibl::MirrorBallView& view = ctx.view;
  const glm::dvec3 implied = tracking::probeCenterForImageShift(view.pose, view.camera, view.center_w, fit.shift_px);
  probe_center_offset_w_ += config.weight * (implied - view.center_w);
  probe_radius_scale_ *= 1.0 + config.weight * (fit.radius_scale - 1.0);
}

void TrackStage::writeReport(nlohmann::json& report) const {
  report["tag_status"] = {{"frames", tag_status_frames_},
                          {"last_problem", last_tag_problem_},
                          {"refinement_reused_frames", refinement_reused_frames_}};
  nlohmann::json refinement = {{"enabled", settings_.probe_refinement.enabled},
                               {"fits", probe_fits_},
                               {"refused", probe_fits_refused_},
                               {"center_offset_mm", {1000.0 * probe_center_offset_w_.x, 1000.0 * probe_center_offset_w_.y,
                                                     1000.0 * probe_center_offset_w_.z}},
                               {"radius_scale", probe_radius_scale_}};
  if (!probe_fit_shift_px_.empty()) refinement["fit_shift_px_median"] = probe_fit_shift_px_.median();
  if (!probe_fit_last_refusal_.empty()) refinement["last_refusal"] = probe_fit_last_refusal_;
  report["probe_refinement"] = refinement;
}

}  // namespace probelight
