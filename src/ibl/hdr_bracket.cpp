#include "ibl/hdr_bracket.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace probelight::ibl {
namespace {

// Decoded linear value of every 8-bit code, once.
std::array<double, 256> decodeTable(const CameraTransfer& transfer) {
  std::array<double, 256> table{};
  for (int code = 0; code < 256; ++code) table[static_cast<size_t>(code)] = decodeCameraValue(transfer, code / 255.0);
  return table;
}

double hatWeight(int code, const HdrMergeSettings& settings) {
  if (code <= settings.dark_code || code >= settings.clip_code) return 0.0;
  return static_cast<double>(std::min(code - settings.dark_code, settings.clip_code - code));
}

}  // namespace

double clippedMapLevel(const HdrMergeSettings& settings, double probe_reflectance) {
  return decodeCameraValue(settings.camera_transfer, settings.clip_code / 255.0) / probe_reflectance;
}

std::string bracketProblem(const std::vector<BracketFrame>& frames) {
  if (frames.empty()) return "an exposure bracket needs at least one frame";
  const ImageRGB8* first = frames.front().image;
  for (const BracketFrame& frame : frames) {
    if (!frame.image || frame.image->empty()) return "a bracket frame is empty";
    if (frame.image->width != first->width || frame.image->height != first->height)
      return "bracket frames differ in size (" + std::to_string(first->width) + "x" + std::to_string(first->height) +
             " and " + std::to_string(frame.image->width) + "x" + std::to_string(frame.image->height) + ")";
    if (!std::isfinite(frame.ev) || std::abs(frame.ev) > 24.0) return "a bracket EV is not a number within +-24 stops";
  }
  return "";
}

HdrMergeResult mergeBracket(const std::vector<BracketFrame>& frames, const HdrMergeSettings& settings) {
  HdrMergeResult result;
  if (!bracketProblem(frames).empty()) return result;
  const std::array<double, 256> linear = decodeTable(settings.camera_transfer);
  const int width = frames.front().image->width, height = frames.front().image->height;
  result.linear.resize(width, height);
  result.still_clipped.assign(static_cast<size_t>(width) * static_cast<size_t>(height), 0);
  // The shortest and longest exposures, for channels no frame measured.
  size_t shortest = 0, longest = 0;
  std::vector<double> ratios;
  for (size_t f = 0; f < frames.size(); ++f) {
    ratios.push_back(std::exp2(frames[f].ev));
    if (frames[f].ev < frames[shortest].ev) shortest = f;
    if (frames[f].ev > frames[longest].ev) longest = f;
  }
  const size_t pixel_count = static_cast<size_t>(width) * static_cast<size_t>(height);
  // A pixel with any channel clipped counts in none: a camera's colour
  // matrix mixes its channels, and a clipped Y' decodes through the chroma
  // to channels below the clip (probe_to_cube.cpp says more).
  auto clipped = [&](size_t f, size_t i) {
    const std::uint8_t* code = &frames[f].image->pixels[3 * i];
    return std::max({code[0], code[1], code[2]}) >= settings.clip_code;
  };
  for (size_t i = 0; i < pixel_count; ++i) {
    glm::vec3 merged(0.0f);
    for (int c = 0; c < 3; ++c) {
      double weighted = 0.0, weight_sum = 0.0;
      for (size_t f = 0; f < frames.size(); ++f) {
        if (clipped(f, i)) continue;
        const int code = frames[f].image->pixels[3 * i + static_cast<size_t>(c)];
        const double weight = hatWeight(code, settings) * ratios[f];
        weighted += weight * linear[static_cast<size_t>(code)] / ratios[f];
        weight_sum += weight;
      }
      if (weight_sum > 0.0) {
        merged[c] = static_cast<float>(weighted / weight_sum);
        continue;
      }
      const int short_code = frames[shortest].image->pixels[3 * i + static_cast<size_t>(c)];
      if (clipped(shortest, i)) {
        merged[c] = static_cast<float>(linear[static_cast<size_t>(short_code)] / ratios[shortest]);
        result.still_clipped[i] = 1;
      } else {
        const int long_code = frames[longest].image->pixels[3 * i + static_cast<size_t>(c)];
        merged[c] = static_cast<float>(linear[static_cast<size_t>(long_code)] / ratios[longest]);
      }
    }
    result.linear.pixels[i] = merged;
  }
  return result;
}

std::optional<double> measureExposureRatio(const ImageRGB8& reference, const ImageRGB8& shorter,
                                           const HdrMergeSettings& settings, int min_samples) {
  if (reference.empty() || reference.width != shorter.width || reference.height != shorter.height) return std::nullopt;
  const std::array<double, 256> linear = decodeTable(settings.camera_transfer);
  // Well exposed in both: away from the clip and well above the noise (a
  // few codes of noise on a dark value would swing the ratio).
  const int floor_code = std::max(settings.dark_code, 24);
  // A ratio depends only on the two codes: count the code pairs, then walk
  // the distinct pairs in order of their ratio to the median (the same
  // element a sort of every channel's ratio would give, without a million
  // of them to sort).
  std::vector<std::uint32_t> pair_count(256 * 256, 0);
  long samples = 0;
  for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
    const int a = reference.pixels[i], b = shorter.pixels[i];
    if (a >= settings.clip_code || b >= settings.clip_code || a <= floor_code || b <= floor_code) continue;
    ++pair_count[static_cast<std::size_t>(a) * 256 + static_cast<std::size_t>(b)];
    ++samples;
  }
  if (samples < min_samples) return std::nullopt;
  std::vector<std::pair<double, std::uint32_t>> ratios;  // ratio, channels with it
  for (std::size_t a = 0; a < 256; ++a)
    for (std::size_t b = 0; b < 256; ++b)
      if (const std::uint32_t count = pair_count[a * 256 + b]; count > 0) ratios.emplace_back(linear[b] / linear[a], count);
  std::sort(ratios.begin(), ratios.end());
  long seen = 0;
  for (const auto& [ratio, count] : ratios) {
    seen += count;
    if (seen > samples / 2) return ratio;
  }
  return ratios.back().first;
}

}  // namespace probelight::ibl
