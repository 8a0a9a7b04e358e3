#include "stages/blur_match_stage.hpp"

#include <chrono>
#include <cmath>

#include "stages/stage_settings.hpp"

namespace probelight {

BlurMatchStage::BlurMatchStage(const CameraMatchConfig& config, const CameraIntrinsics& camera,
                               const RigGeometry& rig, const ibl::CameraTransfer& camera_transfer, RunReport& report)
    : config_(config), camera_(camera), report_(report) {
  settings_.camera_transfer = camera_transfer;
  if (const std::optional<ibl::TagCellGrid> grid = tagCellGridOf(rig)) {
    border_half_m_ = rig.tag_size_m / 2.0;
    cell_m_ = grid->cell_m;
  }
}

void BlurMatchStage::run(const tracking::TagTrackResult& track, const FrameBuffer& frame) {
  if (!config_.blur) return skip("off");
  if (!(cell_m_ > 0.0)) return skip("no_tag_grid");
  if (!track.found) return skip("no_tag");
  if (edge_sigma_px_ && ++frames_since_measured_ < kMeasureEveryFrames) return skip("measured_recently");
  // A frame it cannot measure is a skip, with the reason; not timed.
  const auto start = std::chrono::steady_clock::now();
  const ibl::EdgeBlurReading reading = ibl::measureEdgeBlur(
      camera_, track.pose, border_half_m_, cell_m_, [&frame](int x, int y) { return frame.rgbAt(x, y); }, settings_);
  if (reading.status != ibl::EdgeBlurStatus::kMeasured) return skip(ibl::toString(reading.status));
  frames_since_measured_ = 0;
  const double variance = reading.edge_sigma_px * reading.edge_sigma_px;
  edge_sigma_px_ = edge_sigma_px_ ? std::sqrt(*edge_sigma_px_ * *edge_sigma_px_ +
                                              config_.blur_smoothing_new_weight * (variance - *edge_sigma_px_ * *edge_sigma_px_))
                                  : reading.edge_sigma_px;
  report_.recordStageMs(kStageName,
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  nlohmann::json& out = report_.extra["camera_match"]["blur"];
  out["edge_sigma_px"] = *edge_sigma_px_;
  out["ten_to_ninety_px"] = 2.0 * 1.2815515655446004 * *edge_sigma_px_;
  out["last_frame"] = {{"edge_sigma_px", reading.edge_sigma_px}, {"sides", reading.sides}, {"samples", reading.samples}};
}

}  // namespace probelight
