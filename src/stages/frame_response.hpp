// The camera's response a frame was taken with, as far as its metadata
// says: camera-linear values are light times the exposure (time x analogue
// gain) and, per channel, the white balance's colour gains. Auto exposure
// and auto white balance move these from frame to frame, so values
// measured in one frame (the maps, the fitted lights) are brought into
// another's units by the per-channel ratio of the two responses (issue 19:
// the object follows the camera's own response). Pure.
#pragma once

#include <glm/glm.hpp>

#include "capture/frame_source.hpp"

namespace probelight {

// Each field 0 when the source cannot say.
struct FrameResponse {
  double exposure_product = 0.0;  // exposure time (us) x analogue gain (1 when unknown)
  double red_gain = 0.0;          // the white balance's colour gains (green is 1)
  double blue_gain = 0.0;
};

FrameResponse frameResponseOf(const FrameMetadata& metadata);

// Per channel, what a camera-linear value measured under `from` reads under
// `to`: each factor (exposure, red, blue) 1 where either response cannot
// say it, so a source without metadata changes nothing.
glm::dvec3 responseRatio(const FrameResponse& from, const FrameResponse& to);

}  // namespace probelight
