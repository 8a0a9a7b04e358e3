#include "stages/shadows_stage.hpp"

#include <algorithm>
#include <string>

#include "stages/gpu_stage_timer.hpp"
#include "stages/stage_settings.hpp"

namespace probelight {

ShadowsStage::ShadowsStage(const PipelineSettings& settings, const ibl::ShadowCaster& caster, RunReport& report)
    : settings_(settings), caster_(caster), report_(report) {}

Status ShadowsStage::init(const gles::Capabilities& capabilities) {
  std::string error;
  passes::GroundShadowSettings shadow_settings = groundShadowSettings(settings_);
  // A model shadows itself too (ComposeStage hands it the near-side maps),
  // unless probelight.yaml's object.self_shadow says not to.
  shadow_settings.self_shadow_maps = caster_.shape == ibl::ShadowCaster::Shape::kMesh && settings_.object.self_shadow;
  if (enabled() && !pass_.init(capabilities, shadow_settings, error))
    return Status::runtimeFailure("GPU set-up failed: " + error);
  return Status::ok();
}

Status ShadowsStage::run(std::uint64_t frame_number, const std::vector<ibl::DomeLight>& dome_now,
                         std::size_t dome_size) {
  if (!enabled() || dome_now.empty()) return Status::ok();
  const std::vector<ibl::ShadowLight> lights = ibl::groundShadowLights(dome_now);
  const bool same = drawn_ && lights.size() == shown_.size() &&
                    std::equal(lights.begin(), lights.end(), shown_.begin(),
                               [](const ibl::ShadowLight& a, const ibl::ShadowLight& b) {
                                 return a.direction_w == b.direction_w && a.share_rgb == b.share_rgb &&
                                        a.cone_radius_rad == b.cone_radius_rad;
                               });
  // Lights below the horizon or too faint never get a pass.
  report_.count("shadow_lights_too_faint", std::max(0, static_cast<int>(dome_size) - static_cast<int>(lights.size())));
  if (same && !settings_.lights.shadows_every_frame) {
    report_.count("shadow_passes_skipped", static_cast<long long>(lights.size()));
    return Status::ok();
  }
  {
    GpuStageTimer timer(report_, kStageName, settings_.gpu_finish);
    std::string error;
    if (!pass_.update(lights, caster_, error)) return Status::runtimeFailure(error);
  }
  report_.count("shadow_passes_run", pass_.shadowPassesLastUpdate());
  report_.count("shadow_updates");
  last_update_frame_ = frame_number;
  shown_ = lights;
  drawn_ = true;
  return Status::ok();
}

// Shadow maps are made only when the lights (fading after a fit) or the
// object change: passes run and skipped (a skipped pass is a light whose map
// from an earlier frame still holds), and the last frame that made any.
void ShadowsStage::writeReport(nlohmann::json& report) const {
  report["shadows"] = {{"enabled", enabled()},
                       {"depth_storage", enabled() ? pass_.depthStorageDescription() : ""},
                       {"passes_run", report_.counter("shadow_passes_run")},
                       {"passes_skipped", report_.counter("shadow_passes_skipped")},
                       {"updates", report_.counter("shadow_updates")},
                       {"last_update_frame", last_update_frame_}};
}

}  // namespace probelight
