// Motion blur matched to the frame (issue 19): while the camera moves, the
// room in the frame is smeared along its motion over the exposure time,
// and the object is given the same smear. Each frame with the tag in view,
// the object's centre is projected with the frame's (smoothed) pose and its
// on-screen velocity found from the last frames (stages/screen_motion.hpp);
// velocity x the frame's exposure time (its metadata) is the smear the
// compose stage draws the object with (passes/object_blur.hpp's box along
// the smear). One vector for the whole object: a camera turning about its
// viewing axis smears an object's sides unequally, and a rolling shutter's
// skew is left out.
//
// Skips: off, no_tag, unknown_exposure_time (the frame's metadata has
// none), no_previous_frame (the first tracked frame of a motion), still
// (the smear is under kShortestSmearPx), and the pipeline's own
// (exposure_bracket).
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "capture/frame_source.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"
#include "stages/screen_motion.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

class MotionMatchStage {
 public:
  static constexpr const char* kStageName = "match_motion";
  // A box this long adds 0.5^2 / 12 = 0.02 px^2 of variance to an edge: a
  // quarter of the pixel's own (1/12). Shorter smears are not drawn.
  static constexpr double kShortestSmearPx = 0.5;

  // object_centre_w: the point whose motion stands for the object's.
  MotionMatchStage(const CameraMatchConfig& config, const CameraIntrinsics& camera, const glm::dvec3& object_centre_w,
                   RunReport& report)
      : config_(config), camera_(camera), object_centre_w_(object_centre_w), report_(report) {}

  // `time_s`: the frame's timestamp.
  void run(const tracking::TagTrackResult& track, const FrameMetadata& metadata, double time_s);
  // A frame the pipeline does not run on: the frame shown again keeps its smear.
  void skip(const std::string& reason) { report_.recordStageSkip(kStageName, reason); }

  // The smear (px) to give the object shown now; none when still or unknown.
  std::optional<glm::dvec2> smearPx() const { return smear_px_; }

 private:
  void skipUnsmeared(const std::string& reason) {
    smear_px_.reset();
    skip(reason);
  }

  CameraMatchConfig config_;
  CameraIntrinsics camera_;
  glm::dvec3 object_centre_w_;
  RunReport& report_;
  ScreenMotion motion_;
  std::optional<glm::dvec2> smear_px_;
  double longest_smear_px_ = 0.0;
};

}  // namespace probelight
