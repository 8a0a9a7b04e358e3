// The track stage: the tag and its pose (libapriltag, corner refinement,
// IPPE, the flip settled over frames: tracking/tag_tracker), the pose
// smoothed (tracking/pose_smoother), the ball's outline through it, and
// probe refinement: the rig's ball position and radius corrected, over
// frames, toward where the image shows it (tracking/probe_edge_fit).
#pragma once

#include <map>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "core/status.hpp"
#include "core/types.hpp"
#include "stages/frame_context.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"
#include "tracking/pose_smoother.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

class TrackStage {
 public:
  static constexpr const char* kStageName = "detect_pose";
  static constexpr const char* kRefineStageName = "probe_refine";

  // `fit_probe_edges`: fit the ball's outline to the image on every frame
  // that shows it whole (ctx.probe_edge_fit), even with probe refinement
  // off (analyze reports it).
  TrackStage(const PipelineSettings& settings, const RigGeometry& rig, const CameraIntrinsics& camera,
             RunReport& report, bool fit_probe_edges = false);
  // Builds the tracker: bad tracking settings are bad input.
  Status init();

  void run(FrameContext& ctx);
  // A frame the pipeline does not run on: not looked at, and counted.
  void skip(const std::string& reason);
  // Forgets the tag's history, the smoothing and the refinement (a frame
  // analysed again must give the same answer).
  void reset();

  // report.json: tag_status (frames per tracking status, the last problem)
  // and probe_refinement.
  void writeReport(nlohmann::json& report) const;

 private:
  void refineProbe(FrameContext& ctx);

  const PipelineSettings& settings_;
  RigGeometry rig_;
  CameraIntrinsics camera_;
  RunReport& report_;
  bool fit_probe_edges_;
  std::unique_ptr<tracking::TagTracker> tracker_;
  std::unique_ptr<tracking::PoseSmoother> smoother_;
  std::map<std::string, long long> tag_status_frames_;
  long long refinement_reused_frames_ = 0;  // frames that kept a still tag's refinement
  nlohmann::json last_tag_problem_;  // null until a frame's tag is not usable
  // probe_refinement's correction of rig.yaml's ball, and its record.
  glm::dvec3 probe_center_offset_w_{0.0};
  double probe_radius_scale_ = 1.0;
  long long probe_fits_ = 0, probe_fits_refused_ = 0;
  SampleSeries probe_fit_shift_px_;
  std::string probe_fit_last_refusal_;
};

}  // namespace probelight
