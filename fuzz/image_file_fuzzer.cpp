// A camera frame from a file (readImageFile, as analyze and --source images
// read them): a decoded image no larger than the size limit, or nothing with
// a reason. The header is checked before anything is decoded.
#include <opencv2/imgcodecs.hpp>

#include "capture/rgb_image_io.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The extension does not choose the decoder (OpenCV looks at the bytes);
  // .png keeps the name a frame's usual one.
  const std::string path = fuzz::writeInput(data, size, "frame.png");
  std::string why;
  const cv::Mat image = readImageFile(path, cv::IMREAD_COLOR, &why);
  if (image.empty()) {
    fuzz::require(!why.empty() && why.find('\n') == std::string::npos, "no image and no one-line reason");
    return 0;
  }
  fuzz::require(image.cols <= kMaxImageSidePx && image.rows <= kMaxImageSidePx, "an image above 8192 px decoded");
  fuzz::require(image.type() == CV_8UC3, "IMREAD_COLOR gave no 8-bit BGR image");
  return 0;
}
