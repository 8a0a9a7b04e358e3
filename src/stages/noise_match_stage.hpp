// Noise matched to the frame (issue 19): each frame with the tag in view,
// the frame's noise is measured on the tag's flat cells
// (ibl::measureSensorNoise) at the black and the white ink's level, and
// kept smoothed over frames; the compose stage adds noise of that
// statistic to the object's pixels only (passes/camera_response.hpp).
//
// A frame that cannot be measured (no tag, a tag too small in the image to
// have flat cell interiors, cells that do not show two flat inks) keeps
// the last estimate; a change of the sensor's analogue gain by more than
// kGainChangeFraction restarts the smoothing, since the noise changes with
// it at once.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "capture/frame_source.hpp"
#include "ibl/sensor_noise.hpp"
#include "passes/camera_response.hpp"
#include "stages/pipeline_settings.hpp"
#include "stages/run_report.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

// Pure: the kept estimate, a level at a time, smoothed over frames.
class NoiseEstimateSmoother {
 public:
  static constexpr double kGainChangeFraction = 0.05;
  explicit NoiseEstimateSmoother(double new_weight) : new_weight_(new_weight) {}
  // A measured frame (reading.status kMeasured) at this analogue gain (0:
  // unknown, never a restart).
  void add(const ibl::SensorNoiseReading& reading, double analogue_gain);
  bool has() const { return dark_.has_value(); }
  const ibl::NoiseAtLevel& dark() const { return *dark_; }
  const ibl::NoiseAtLevel& bright() const { return *bright_; }
  int restarts() const { return restarts_; }

 private:
  double new_weight_;
  std::optional<ibl::NoiseAtLevel> dark_, bright_;
  double gain_ = 0.0;
  int restarts_ = 0;
};

class NoiseMatchStage {
 public:
  static constexpr const char* kStageName = "match_noise";

  NoiseMatchStage(const CameraMatchConfig& config, const CameraIntrinsics& camera, const RigGeometry& rig,
                  RunReport& report);

  bool enabled() const { return config_.noise; }
  // Measures `frame`'s noise where `track` puts the tag. Records a run, or a
  // skip with its reason: off, no_tag, no_tag_grid, or the measurement's
  // status (not_in_view, too_small, not_flat).
  void run(const tracking::TagTrackResult& track, const FrameBuffer& frame, std::uint64_t frame_number);
  void skip(const std::string& reason) { report_.recordStageSkip(kStageName, reason); }

  // What the compose stage adds this frame; null when off or before the
  // first measurement.
  const passes::SensorNoiseMatch* match() const { return match_ ? &*match_ : nullptr; }

 private:
  void reportEstimate();

  CameraMatchConfig config_;
  CameraIntrinsics camera_;
  std::optional<ibl::TagCellGrid> grid_;
  RunReport& report_;
  NoiseEstimateSmoother smoother_;
  std::optional<passes::SensorNoiseMatch> match_;
  ibl::SensorNoiseSettings settings_;
};

}  // namespace probelight
