#include "stages/frame_response.hpp"

#include <cmath>

#include "stages/clipped_light_follower.hpp"

namespace probelight {

namespace {

// to / from where both are known (finite and positive), else 1.
double factor(double from, double to) {
  const bool known = std::isfinite(from) && std::isfinite(to) && from > 0.0 && to > 0.0;
  return known ? to / from : 1.0;
}

}  // namespace

FrameResponse frameResponseOf(const FrameMetadata& metadata) {
  FrameResponse response;
  if (metadata.exposure_us > 0.0) response.exposure_product = exposureProduct(metadata.exposure_us, metadata.analogue_gain);
  response.red_gain = metadata.red_gain;
  response.blue_gain = metadata.blue_gain;
  return response;
}

glm::dvec3 responseRatio(const FrameResponse& from, const FrameResponse& to) {
  const double exposure = factor(from.exposure_product, to.exposure_product);
  return exposure * glm::dvec3(factor(from.red_gain, to.red_gain), 1.0, factor(from.blue_gain, to.blue_gain));
}

}  // namespace probelight
