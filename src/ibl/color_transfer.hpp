// Camera transfer functions. Camera images are sRGB-encoded by default; all
// lighting maths happens in linear light.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

namespace probelight::ibl {

// The BT.709 luminance weights applied to three per-channel quantities
// (numbers, or vectors such as a light's first moment per channel).
template <typename T>
T luminanceWeighted(const T& r, const T& g, const T& b) {
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

// Relative luminance of linear Rec.709 / sRGB primaries (ITU-R BT.709).
inline double luminance(const glm::dvec3& rgb) { return luminanceWeighted(rgb.r, rgb.g, rgb.b); }

// IEC 61966-2-1 piecewise sRGB curve, values in [0, 1].
double srgbToLinear(double encoded);
double linearToSrgb(double linear);

// 8-bit sRGB codes without a pow per value (an 8-bit cube map's 24576
// texels x 3 channels each way): srgbCodeToLinear(code) is
// srgbToLinear(code / 255.0), from a table; linearToSrgbCode(linear) is
// lround(255 * linearToSrgb(linear)), from the linear level at which each
// code begins, found once by bisecting that very expression (so the two
// agree exactly, boundaries included).
double srgbCodeToLinear(std::uint8_t code);
std::uint8_t linearToSrgbCode(double linear);

// How the camera encodes light in its 8-bit values (its "transfer"). sRGB is
// what libcamera's YUV and most webcams deliver; a camera tuned to a plain
// power law, or one delivering linear values, is configured here.
struct CameraTransfer {
  enum class Curve { kSrgb, kGamma, kLinear };
  Curve curve = Curve::kSrgb;
  double gamma = 2.2;  // kGamma only: linear = encoded ^ gamma
};

// Encoded value in [0, 1] (clamped) to linear light in [0, 1].
double decodeCameraValue(const CameraTransfer& transfer, double encoded);

}  // namespace probelight::ibl
