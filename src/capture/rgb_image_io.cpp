#include "capture/rgb_image_io.hpp"

#include <new>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace probelight {

void rgbFromBgr(const cv::Mat& bgr, ImageRGB8& rgb) {
  rgb.resize(bgr.cols, bgr.rows);
  cv::Mat view(bgr.rows, bgr.cols, CV_8UC3, rgb.pixels.data());
  cv::cvtColor(bgr, view, cv::COLOR_BGR2RGB);
}

ImageRGB8 rgbFromBgr(const cv::Mat& bgr) {
  ImageRGB8 rgb;
  rgbFromBgr(bgr, rgb);
  return rgb;
}

cv::Mat bgrFromRgb(const ImageRGB8& rgb) {
  const cv::Mat view(rgb.height, rgb.width, CV_8UC3, const_cast<std::uint8_t*>(rgb.pixels.data()));
  cv::Mat bgr;
  cv::cvtColor(view, bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

bool writeRgbImage(const std::string& path, const ImageRGB8& rgb, const std::vector<int>& params) {
  try {
    return cv::imwrite(path, bgrFromRgb(rgb), params);
  } catch (const cv::Exception&) {
    return false;  // an extension OpenCV cannot write
  }
}

cv::Mat readImageFile(const std::string& path, int imread_flags) {
  try {
    return cv::imread(path, imread_flags);
  } catch (const cv::Exception&) {
    return cv::Mat();
  } catch (const std::bad_alloc&) {
    return cv::Mat();  // a header within OpenCV's limit that still does not fit in memory
  }
}

}  // namespace probelight
