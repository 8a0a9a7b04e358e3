// The shadows stage: the object's soft shadow on the real ground from the
// dome of lights (passes/ground_shadow: a shadow map per light, and the
// fraction of the ground's light that still reaches each ground point).
// Made again only when the lights shown (fading after a fit) or the object
// change: a still scene renders no shadow map, and the camera's motion needs
// none (the shadow lies on the ground, not on the screen).
#pragma once

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/status.hpp"
#include "gles/capabilities.hpp"
#include "ibl/ground_shadow.hpp"
#include "ibl/light_dome.hpp"
#include "passes/ground_shadow.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"

namespace probelight {

class ShadowsStage {
 public:
  static constexpr const char* kStageName = "shadows";

  ShadowsStage(const PipelineSettings& settings, const ibl::ShadowCaster& caster, RunReport& report);
  // Nothing to set up when lights.shadows is off.
  Status init(const gles::Capabilities& capabilities);

  // `dome_now`: the lights shown now; `dome_size`: how many the fit made
  // (those too faint or below the horizon never get a pass).
  Status run(std::uint64_t frame_number, const std::vector<ibl::DomeLight>& dome_now, std::size_t dome_size);

  bool enabled() const { return settings_.lights.shadows; }
  // The pass, to composite the shadow over the camera image and read it.
  const passes::GroundShadow& pass() const { return pass_; }
  passes::GroundShadow& pass() { return pass_; }
  std::size_t lightsCasting() const { return shown_.size(); }

  // report.json: shadows (passes run and skipped, the last frame that made any).
  void writeReport(nlohmann::json& report) const;

 private:
  const PipelineSettings& settings_;
  ibl::ShadowCaster caster_;
  RunReport& report_;
  passes::GroundShadow pass_;
  std::vector<ibl::ShadowLight> shown_;  // what the shadow maps show
  bool drawn_ = false;
  std::uint64_t last_update_frame_ = 0;
};

}  // namespace probelight
