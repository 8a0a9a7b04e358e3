// The maps stage: the ball's image to a world-aligned reflection cube map,
// the diffuse map from it (the cosine passes, or SH9:
// environment_maps.diffuse_method), and the glossy levels where the object's
// material reads them (passes/environment_maps). Remade only when the update
// policy says the frame shows something new (stages/map_update_policy.hpp);
// otherwise the last good maps stay, and the frame is counted as skipped
// with its reason.
//
// With environment_maps.merge_views, each remade reflection map (and the
// frame around its ball) is merged into a probe over views
// (stages/probe_merge.hpp), and the maps show the merged probe: the
// directions one view hides behind its ball come from the views that saw
// them. A view that moves no texel of the probe beyond its noise leaves the
// diffuse and glossy maps as they are ("probe unchanged").
#pragma once

#include <array>
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
#include "stages/frame_response.hpp"
#include "stages/map_update_policy.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/probe_merge.hpp"
#include "stages/run_report.hpp"

namespace probelight {

class MapsStage {
 public:
  static constexpr const char* kReflectionStageName = "probe_to_cube";
  static constexpr const char* kGlossyStageName = "glossy";
  static constexpr const char* kMergeStageName = "probe_merge";
  // A relative irradiance change at the axis normals that keeps every
  // normal below half an 8-bit display code (see mergeIntoProbe): the
  // diffuse map is not remade for less.
  static constexpr double kInvisibleIrradianceChange = 0.0025;

  // object_reads_glossy: whether the object's material reads a glossy map
  // (SceneObject::readsGlossy): they are made only then. merge_views: the
  // views are merged into a probe (environment_maps.merge_views; analyze
  // merges its views itself).
  MapsStage(const PipelineSettings& settings, const RigGeometry& rig, bool object_reads_glossy, bool merge_views,
            RunReport& report);
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

  // merge_views: a recalibration's merged bracket (in the maps' units at
  // `exposure_product`; still_clipped its flags) goes into the probe, and the
  // maps are remade from it.
  Status mergeBracket(const ibl::MirrorBallView& view, const ibl::CubeMapRGB& hdr,
                      const std::vector<std::uint8_t>& still_clipped, double exposure_product);
  // The merged probe (null without merge_views).
  const ProbeMerge* probe() const { return probe_ ? &*probe_ : nullptr; }
  // The probe kept in state.dir (stages/state_store): saved with each fit,
  // loaded at start-up. A missing file is normal; a bad one is said (as the
  // returned warning) and the kiosk starts without it.
  bool saveProbe(const std::string& state_dir, std::string& error);
  std::string loadStoredProbe(const std::string& state_dir);
  // The report names the diffuse stage after the method that runs.
  const char* diffuseStageName() const;
  bool haveMaps() const { return have_maps_; }
  const passes::EnvironmentMaps& maps() const { return maps_; }
  passes::EnvironmentMaps& maps() { return maps_; }  // to draw with (binds its textures)
  // The view the current maps were made from (none before the first).
  const std::optional<ibl::MirrorBallView>& mapsView() const { return maps_view_; }
  int framesSinceUpdate() const { return policy_.framesSinceUpdate(); }
  // The camera's response in the frame the maps were last made from: their
  // camera-linear values are in its units (with merge_views the probe
  // follows each merged frame's exposure; a bracket's merge keeps the
  // probe's units). 0s before any, or from a source that cannot say.
  const FrameResponse& mapsResponse() const { return maps_response_; }
  // The camera's response in the frame the lights in use were fitted in
  // (none while a recalibration runs): the probe's map shows the light
  // below that frame's clip level, the clipped lights the rest.
  void setLightsFittedAt(const std::optional<FrameResponse>& response) { lights_fitted_at_ = response; }
  // The reflection map's largest channel value (its other maps are means
  // of it): the probe's, as uploaded; a map made on the GPU from one frame
  // holds at most the 8-bit white through the ball's reflectance.
  double reflectionPeak() const { return reflection_peak_; }

  // report.json: map_updates (updates by cause, skips by reason, what the
  // policy measured) and map_storage.
  void writeReport(nlohmann::json& report) const;

 private:
  Status remake(const ibl::MirrorBallView& view, const passes::CameraFrameTexture& frame, const FrameBuffer& pixels,
                float new_weight);
  // The reflection map just made, merged into the probe; the probe's map
  // replaces it. Says whether the diffuse and the glossy maps must be
  // remade (else they already hold the probe, to within what shows).
  Status mergeIntoProbe(const ibl::MirrorBallView& view, const FrameBuffer& pixels, bool& diffuse_due,
                        bool& glossy_due);
  // The probe's live map becomes the reflection map.
  Status showProbe();
  // The diffuse map (blended by new_weight) and the glossy levels from the
  // current reflection map (each only when asked; timed as their stages
  // unless the caller times them).
  Status remakeFromReflection(float new_weight, bool diffuse = true, bool glossy = true, bool timed = true);
  void record(const MapUpdateDecision& decision);

  const PipelineSettings& settings_;
  double probe_reflectance_;
  bool object_reads_glossy_;
  std::optional<ProbeMerge> probe_;  // merge_views only
  RunReport& report_;
  passes::EnvironmentMaps maps_;
  MapUpdatePolicy policy_;
  bool have_maps_ = false;
  FrameResponse maps_response_;
  std::optional<FrameResponse> lights_fitted_at_;
  double reflection_peak_ = 0.0;
  std::optional<ibl::MirrorBallView> maps_view_;
  std::map<std::string, long long> update_causes_;
  std::map<std::string, long long> skip_reasons_;
  nlohmann::json probe_report_;  // merge_views: totals of what the views did
  ibl::AccumulateCounts probe_totals_;
  // The probe's irradiance at the axis normals when the diffuse map was
  // made from it (ProbeMerge::axisIrradiance).
  std::array<double, 6> axis_irradiance_at_diffuse_{};
  long long probe_views_ = 0, probe_views_unchanged_ = 0, probe_frame_texels_ = 0, probe_brackets_ = 0;
  SampleSeries center_shift_px_, radius_change_px_, rotation_change_deg_, image_change_code_;
};

}  // namespace probelight
