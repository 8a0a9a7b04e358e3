#include "stages/response_match_stage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace probelight {

void ResponseMatchStage::skip(const std::string& reason) { report_.recordStageSkip(kStageName, reason); }

void ResponseMatchStage::skipWithUnitGain(const std::string& reason) {
  gain_rgb_ = glm::dvec3(1.0);
  skip(reason);
}

void ResponseMatchStage::run(const FrameBuffer& frame, const MapsStage& maps, std::uint64_t frame_number) {
  if (!config_.response) return skipWithUnitGain("off");
  if (!maps.haveMaps()) return skipWithUnitGain("no_maps");
  const FrameResponse now = frameResponseOf(frame.metadata);
  if (!(now.exposure_product > 0.0) && !(now.red_gain > 0.0) && !(now.blue_gain > 0.0))
    return skipWithUnitGain("unknown_response");
  const auto start = std::chrono::steady_clock::now();
  gain_rgb_ = responseRatio(maps.mapsResponse(), now);
  report_.recordStageMs(kStageName,
                        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  const double stops = std::log2(gain_rgb_.g);
  lowest_stops_ = std::min(lowest_stops_, stops);
  highest_stops_ = std::max(highest_stops_, stops);
  nlohmann::json& out = report_.extra["camera_match"]["response"];
  out["frame"] = frame_number;
  out["gain_rgb"] = {gain_rgb_.r, gain_rgb_.g, gain_rgb_.b};
  out["stops_from_maps"] = {{"lowest", lowest_stops_}, {"highest", highest_stops_}};
}

}  // namespace probelight
