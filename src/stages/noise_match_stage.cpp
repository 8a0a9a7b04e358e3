#include "stages/noise_match_stage.hpp"

#include <chrono>
#include <cmath>

#include "stages/stage_settings.hpp"

namespace probelight {

namespace {

// Smoothing in variance, the quantity that averages: sigma^2 of the
// estimate, the level's codes alike.
void blendLevel(ibl::NoiseAtLevel& kept, const ibl::NoiseAtLevel& now, double weight) {
  const glm::dvec3 variance = glm::mix(kept.sigma_code * kept.sigma_code, now.sigma_code * now.sigma_code, weight);
  kept.sigma_code = glm::sqrt(variance);
  kept.mean_code = glm::mix(kept.mean_code, now.mean_code, weight);
  kept.pixels = now.pixels;
  kept.cells = now.cells;
}

nlohmann::json levelJson(const ibl::NoiseAtLevel& level) {
  return {{"code", {level.mean_code.x, level.mean_code.y, level.mean_code.z}},
          {"sigma_code", {level.sigma_code.x, level.sigma_code.y, level.sigma_code.z}},
          {"cells", level.cells},
          {"pixels", level.pixels}};
}

}  // namespace

void NoiseEstimateSmoother::add(const ibl::SensorNoiseReading& reading, double analogue_gain) {
  if (reading.status != ibl::SensorNoiseStatus::kMeasured) return;
  const bool gain_moved = analogue_gain > 0.0 && gain_ > 0.0 &&
                          std::abs(analogue_gain - gain_) > kGainChangeFraction * gain_;
  if (!dark_ || gain_moved) {
    if (dark_) ++restarts_;
    dark_ = reading.dark;
    bright_ = reading.bright;
  } else {
    blendLevel(*dark_, reading.dark, new_weight_);
    blendLevel(*bright_, reading.bright, new_weight_);
  }
  if (analogue_gain > 0.0) gain_ = analogue_gain;
}

NoiseMatchStage::NoiseMatchStage(const CameraMatchConfig& config, const CameraIntrinsics& camera,
                                 const RigGeometry& rig, RunReport& report)
    : config_(config),
      camera_(camera),
      grid_(tagCellGridOf(rig)),
      report_(report),
      smoother_(config.noise_smoothing_new_weight) {}

void NoiseMatchStage::run(const tracking::TagTrackResult& track, const FrameBuffer& frame, std::uint64_t frame_number) {
  if (!config_.noise) return skip("off");
  if (!grid_) return skip("no_tag_grid");
  if (!track.found) return skip("no_tag");
  // A frame it cannot measure is a skip, with the reason; its few tenths
  // of a millisecond are not timed.
  const auto start = std::chrono::steady_clock::now();
  const ibl::SensorNoiseReading reading = ibl::measureSensorNoise(
      camera_, track.pose, *grid_, [&frame](int x, int y) { return frame.rgbAt(x, y); }, settings_);
  if (reading.status != ibl::SensorNoiseStatus::kMeasured) return skip(ibl::toString(reading.status));
  smoother_.add(reading, frame.metadata.analogue_gain);
  match_ = passes::SensorNoiseMatch{ibl::addedNoiseModel(smoother_.dark(), smoother_.bright()), frame_number};
  report_.recordStageMs(kStageName,
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  reportEstimate();
}

void NoiseMatchStage::reportEstimate() {
  nlohmann::json& out = report_.extra["camera_match"]["noise"];
  out["dark"] = levelJson(smoother_.dark());
  out["bright"] = levelJson(smoother_.bright());
  const ibl::AddedNoiseModel& model = match_->model;
  out["added_sigma_code"] = {{"dark", {model.dark_sigma_code.x, model.dark_sigma_code.y, model.dark_sigma_code.z}},
                             {"bright",
                              {model.bright_sigma_code.x, model.bright_sigma_code.y, model.bright_sigma_code.z}}};
  out["gain_restarts"] = smoother_.restarts();
}

}  // namespace probelight
