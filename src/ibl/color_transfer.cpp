#include "ibl/color_transfer.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {

// Inputs are clamped to [0, 1] because that is what an 8-bit render target or
// texture holds; the GPU path cannot see values outside it either.
double srgbToLinear(double encoded) {
  const double c = std::clamp(encoded, 0.0, 1.0);
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

double linearToSrgb(double linear) {
  const double l = std::clamp(linear, 0.0, 1.0);
  return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

double decodeCameraValue(const CameraTransfer& transfer, double encoded) {
  const double clamped = std::clamp(encoded, 0.0, 1.0);
  switch (transfer.curve) {
    case CameraTransfer::Curve::kLinear:
      return clamped;
    case CameraTransfer::Curve::kGamma:
      return std::pow(clamped, transfer.gamma);
    case CameraTransfer::Curve::kSrgb:
      break;
  }
  return srgbToLinear(clamped);
}

}  // namespace probelight::ibl
