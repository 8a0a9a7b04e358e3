#include "ibl/color_transfer.hpp"

#include <algorithm>
#include <array>
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

namespace {

std::uint8_t exactSrgbCode(double linear) {
  return static_cast<std::uint8_t>(std::lround(255.0 * linearToSrgb(linear)));
}

// starts[c - 1]: the smallest linear value that encodes to code c or more.
struct SrgbCodeStarts {
  static constexpr int kBins = 4096;  // of linear [0, 1]: under one code per bin
  std::array<double, 255> starts{};
  std::array<std::uint8_t, kBins + 1> code_at_bin{};  // the code of each bin's lower end

  SrgbCodeStarts() {
    for (int c = 1; c < 256; ++c) {
      double below = 0.0, at = 1.0;  // exactSrgbCode(below) < c <= exactSrgbCode(at)
      for (;;) {
        const double middle = below + 0.5 * (at - below);
        if (middle <= below || middle >= at) break;  // adjacent doubles
        (exactSrgbCode(middle) >= c ? at : below) = middle;
      }
      starts[static_cast<std::size_t>(c - 1)] = at;
    }
    for (int bin = 0; bin <= kBins; ++bin)
      code_at_bin[static_cast<std::size_t>(bin)] = static_cast<std::uint8_t>(
          std::upper_bound(starts.begin(), starts.end(), static_cast<double>(bin) / kBins) - starts.begin());
  }
};

}  // namespace

double srgbCodeToLinear(std::uint8_t code) {
  static const std::array<double, 256> table = [] {
    std::array<double, 256> t{};
    for (int c = 0; c < 256; ++c) t[static_cast<std::size_t>(c)] = srgbToLinear(c / 255.0);
    return t;
  }();
  return table[code];
}

std::uint8_t linearToSrgbCode(double linear) {
  static const SrgbCodeStarts table;
  if (!(linear > 0.0)) return 0;  // NaN too
  if (linear >= 1.0) return 255;
  // From the code at the bin's lower end, up past each code start at or
  // below `linear` (a step or two: a bin spans under one code), rather than
  // a binary search whose branches a CPU cannot predict.
  int code = table.code_at_bin[static_cast<std::size_t>(linear * SrgbCodeStarts::kBins)];
  while (code < 255 && table.starts[static_cast<std::size_t>(code)] <= linear) ++code;
  return static_cast<std::uint8_t>(code);
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
