#include "core/types.hpp"

#include <cmath>

namespace probelight {

void lumaFromRgb(const ImageRGB8& rgb, std::vector<std::uint8_t>& luma) {
  const std::size_t pixel_count = static_cast<std::size_t>(rgb.width) * static_cast<std::size_t>(rgb.height);
  if (rgb.empty() || rgb.pixels.size() < pixel_count * 3u) {
    luma.clear();
    return;
  }
  luma.resize(pixel_count);
  const std::uint8_t* in = rgb.pixels.data();
  std::uint8_t* out = luma.data();
  for (std::size_t i = 0; i < pixel_count; ++i, in += 3) out[i] = lumaCodeOfRgb(in[0], in[1], in[2]);
}

double rotationAngleDeg(const glm::dmat3& a, const glm::dmat3& b) {
  const glm::dmat3 relative = glm::transpose(a) * b;
  const double cosine = (relative[0][0] + relative[1][1] + relative[2][2] - 1.0) / 2.0;
  const glm::dvec3 axis_times_sine(relative[1][2] - relative[2][1], relative[2][0] - relative[0][2],
                                   relative[0][1] - relative[1][0]);
  return glm::degrees(std::atan2(glm::length(axis_times_sine) / 2.0, cosine));
}

}  // namespace probelight
