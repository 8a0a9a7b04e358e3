// Errors against the simulator's truth: the pose, the ball's outline, and
// (every kCheckEveryFrames) the maps against the simulated world's radiance
// and irradiance. An observer of the pipeline that exists only with the
// simulated source; it reads what the stages made and changes nothing. The
// truth is the simulator's own (its ray tracing and brute-force
// integration), never the IBL code it checks.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "ibl/surface_shading.hpp"
#include "sim/world.hpp"
#include "stages/frame_context.hpp"
#include "stages/maps_stage.hpp"
#include "stages/run_report.hpp"

namespace probelight {

class TruthMonitor {
 public:
  // The maps' read-back is not part of the product's frame cost: every
  // tenth frame is plenty for medians.
  static constexpr std::uint64_t kCheckEveryFrames = 10;

  TruthMonitor(std::shared_ptr<const sim::World> world, RunReport& report);

  // After the frame was shown (frames without a truth are ignored).
  // `lighting`: what the object is lit with beside the maps (the clipped
  // lights).
  void observe(const FrameContext& ctx, const MapsStage& maps, const ibl::SceneLighting& lighting);

  // report.json: map_updates.measured.truth_center_shift_px and
  // map_updates.truth_checks (accuracy goes into the report's own section).
  void writeReport(nlohmann::json& report) const;

 private:
  void measureTracking(const FrameTruth& truth, const FrameContext& ctx);
  struct MapErrors {
    // The diffuse map against the 8-bit-visible irradiance.
    double diffuse_vs_clipped = std::nan("");
    // The diffuse map plus the clipped lights (what the object's diffuse
    // term is lit with) against the whole irradiance.
    double lit_vs_hdr = std::nan("");
  };
  // Mean relative errors over the up and the four horizontal normals (NaN
  // when the maps could not be read).
  MapErrors measureMaps(std::uint64_t frame_index, const ibl::MirrorBallView& view, const passes::EnvironmentMaps& maps,
                        const ibl::SceneLighting& lighting);

  std::shared_ptr<const sim::World> world_;
  RunReport& report_;
  // How far the ball really moved since the previous frame: separates the
  // camera's motion from the pose noise in center_shift_px.
  SampleSeries truth_center_shift_px_;
  std::optional<glm::dvec2> previous_truth_center_px_;
  nlohmann::json truth_checks_ = nlohmann::json::array();
};

}  // namespace probelight
