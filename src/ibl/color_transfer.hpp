// Camera transfer functions. Camera images are sRGB-encoded by default; all
// lighting maths happens in linear light.
#pragma once

namespace probelight::ibl {

// IEC 61966-2-1 piecewise sRGB curve, values in [0, 1].
double srgbToLinear(double encoded);
double linearToSrgb(double linear);

}  // namespace probelight::ibl
