// The maps stage: the ball's image to a world-aligned reflection cube map,
// the diffuse map from it (the cosine passes, or SH9:
// environment_maps.diffuse_method), and the glossy levels where the object's
// material reads them (passes/environment_maps). Remade only when the update
// policy says the frame shows something new (stages/map_update_policy.hpp);
// otherwise the last good maps stay, and the frame is counted as skipped
// with its reason.
#pragma once

#include <map>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/status.hpp"
#include "gles/capabilities.hpp"
#include "ibl/surface_shading.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "stages/frame_context.hpp"
#include "stages/map_update_policy.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"

namespace probelight {

class MapsStage {
 public:
  static constexpr const char* kReflectionStageName = "probe_to_cube";
  static constexpr const char* kGlossyStageName = "glossy";

  // object_reads_glossy: whether the object's material reads a glossy map
  // (SceneObject::readsGlossy): they are made only then.
  MapsStage(const PipelineSettings& settings, double probe_reflectance, bool object_reads_glossy, RunReport& report);
  Status init(const gles::Capabilities& capabilities);

  // Decides, and remakes the maps from `frame` (this frame's upload) when the
  // policy says so.
  Status run(FrameContext& ctx, const passes::CameraFrameTexture& frame);
  // A frame the pipeline does not run on: counted as skipped.
  void skip(const std::string& reason);
  // The next frame that can make maps does, unblended (a recalibration
  // fits the lights from a map made now, not from a smoothed old one).
  void requestFreshMap() { policy_.requestFreshMap(); }

  // A reflection map made elsewhere (a probe merged over views, in the
  // reflection map's units; validity 1 where seen) becomes the maps, the
  // diffuse and glossy ones remade from it unblended.
  Status setProbe(const ibl::CubeMapRGB& map, const std::vector<float>& validity);

  // The report names the diffuse stage after the method that runs.
  const char* diffuseStageName() const;
  bool haveMaps() const { return have_maps_; }
  const passes::EnvironmentMaps& maps() const { return maps_; }
  passes::EnvironmentMaps& maps() { return maps_; }  // to draw with (binds its textures)
  // The view the current maps were made from (none before the first).
  const std::optional<ibl::MirrorBallView>& mapsView() const { return maps_view_; }
  int framesSinceUpdate() const { return policy_.framesSinceUpdate(); }

  // report.json: map_updates (updates by cause, skips by reason, what the
  // policy measured) and map_storage.
  void writeReport(nlohmann::json& report) const;

 private:
  Status remake(const ibl::MirrorBallView& view, const passes::CameraFrameTexture& frame, float new_weight);
  // The diffuse map (blended by new_weight) and the glossy levels from the
  // current reflection map.
  Status remakeFromReflection(float new_weight);
  void record(const MapUpdateDecision& decision);

  const PipelineSettings& settings_;
  double probe_reflectance_;
  bool object_reads_glossy_;
  RunReport& report_;
  passes::EnvironmentMaps maps_;
  MapUpdatePolicy policy_;
  bool have_maps_ = false;
  std::optional<ibl::MirrorBallView> maps_view_;
  std::map<std::string, long long> update_causes_;
  std::map<std::string, long long> skip_reasons_;
  SampleSeries center_shift_px_, radius_change_px_, rotation_change_deg_, image_change_code_;
};

}  // namespace probelight
