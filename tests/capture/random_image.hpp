// An image of uniformly random codes: every byte order and chroma mistake
// shows in it.
#pragma once

#include <random>

#include "core/types.hpp"

namespace probelight::testing {

inline ImageRGB8 randomImage(int width, int height, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> code(0, 255);
  ImageRGB8 image;
  image.resize(width, height);
  for (auto& c : image.pixels) c = static_cast<std::uint8_t>(code(random));
  return image;
}

}  // namespace probelight::testing
