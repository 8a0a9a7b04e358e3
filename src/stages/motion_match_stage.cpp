#include "stages/motion_match_stage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "ibl/camera_projection.hpp"

namespace probelight {

void MotionMatchStage::run(const tracking::TagTrackResult& track, const FrameMetadata& metadata, double time_s) {
  if (!config_.motion_blur) return skipUnsmeared("off");
  const auto start = std::chrono::steady_clock::now();
  if (!track.found) {
    motion_.forget();
    return skipUnsmeared("no_tag");
  }
  const glm::dvec3 centre_cam = track.pose.toCamera(object_centre_w_);
  if (!(centre_cam.z > 0.0)) {
    motion_.forget();
    return skipUnsmeared("no_tag");
  }
  motion_.observe(time_s, ibl::projectToPixel(camera_, centre_cam));
  if (!(metadata.exposure_us > 0.0)) return skipUnsmeared("unknown_exposure_time");
  const std::optional<glm::dvec2> smear = motion_.smearPx(metadata.exposure_us * 1e-6);
  if (!smear) return skipUnsmeared("no_previous_frame");
  const double length_px = glm::length(*smear);
  nlohmann::json& out = report_.extra["camera_match"]["motion"];
  longest_smear_px_ = std::max(longest_smear_px_, length_px);
  out["last_smear_px"] = {smear->x, smear->y};
  out["longest_smear_px"] = longest_smear_px_;
  if (!(length_px >= kShortestSmearPx)) return skipUnsmeared("still");
  smear_px_ = smear;
  report_.recordStageMs(kStageName,
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
}

}  // namespace probelight
