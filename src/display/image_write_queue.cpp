#include "display/image_write_queue.hpp"

#include <cstdio>

#include "capture/rgb_image_io.hpp"

namespace probelight {

std::unique_ptr<ImageWriteQueue> makePngWriteQueue() {
  return std::make_unique<ImageWriteQueue>(
      [](const std::string& path, const ImageRGB8& image, std::string& error) { return writeRgbPng(path, image, error); });
}

std::string numberedPngName(const std::string& prefix, std::uint64_t number) {
  char digits[24];
  std::snprintf(digits, sizeof digits, "_%06llu.png", static_cast<unsigned long long>(number));
  std::string name = prefix;  // appended, not `prefix + digits`: GCC 12's false -Wrestrict (bug 105329)
  name += digits;
  return name;
}

}  // namespace probelight
