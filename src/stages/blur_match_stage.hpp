// Blur matched to the frame (issue 19): each frame with the tag in view,
// the frame's edge spread is measured on the tag's border
// (ibl::measureEdgeBlur) and kept smoothed over frames (in variance); the
// compose stage gives the object that blur (passes/object_blur.hpp). A
// frame that cannot be measured keeps the last estimate.
//
// The fit costs about a millisecond of CPU (1700 samples, a few dozen
// iterations), and a lens's blur changes only with its focus: after a
// measurement the next kMeasureEveryFrames - 1 frames skip
// ("measured_recently").
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "capture/frame_source.hpp"
#include "ibl/edge_blur.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

class BlurMatchStage {
 public:
  static constexpr const char* kStageName = "match_blur";
  static constexpr int kMeasureEveryFrames = 8;

  BlurMatchStage(const CameraMatchConfig& config, const CameraIntrinsics& camera, const RigGeometry& rig,
                 const ibl::CameraTransfer& camera_transfer, RunReport& report);

  // Measures `frame`'s blur where `track` puts the tag. Records a run, or a
  // skip with its reason: off, no_tag, no_tag_grid, or the measurement's
  // status (not_in_view, too_small, no_edge), or measured_recently.
  void run(const tracking::TagTrackResult& track, const FrameBuffer& frame);
  void skip(const std::string& reason) { report_.recordStageSkip(kStageName, reason); }

  // The frame's edge spread (px, the pixel's area included) to give the
  // object; none when off or before the first measurement.
  std::optional<double> edgeSigmaPx() const { return edge_sigma_px_; }

 private:
  CameraMatchConfig config_;
  CameraIntrinsics camera_;
  double border_half_m_ = 0.0;
  double cell_m_ = 0.0;
  RunReport& report_;
  ibl::EdgeBlurSettings settings_;
  std::optional<double> edge_sigma_px_;
  int frames_since_measured_ = 0;
};

}  // namespace probelight
