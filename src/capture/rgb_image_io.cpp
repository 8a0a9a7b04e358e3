#include "capture/rgb_image_io.hpp"

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <new>

#include <png.h>
#include <zlib.h>

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

namespace {

// libpng reports errors by longjmp: nothing with a destructor may live in
// the frame that calls setjmp, so the encoding is plain C over a FILE.
// libpng's message lands here.
struct PngErrorSink {
  char message[160] = {0};
};

void pngError(png_structp png, png_const_charp message) {
  auto* sink = static_cast<PngErrorSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof sink->message, "%s", message);
  png_longjmp(png, 1);
}

void pngWarning(png_structp, png_const_charp) {}

bool encodePng(std::FILE* file, const std::uint8_t* pixels, int width, int height, PngErrorSink& sink) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, pngError, pngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
  png_set_compression_level(png, 1);
  png_set_compression_strategy(png, Z_RLE);
  png_write_info(png, info);
  const std::size_t stride = static_cast<std::size_t>(width) * 3;
  for (int y = 0; y < height; ++y) png_write_row(png, const_cast<png_bytep>(pixels + stride * static_cast<std::size_t>(y)));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

bool writeRgbPng(const std::string& path, const ImageRGB8& rgb, std::string& error) {
  if (rgb.width <= 0 || rgb.height <= 0 || rgb.pixels.size() < static_cast<std::size_t>(rgb.width) * rgb.height * 3) {
    error = path + ": no image to write";
    return false;
  }
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) {
    error = path + ": " + std::strerror(errno);
    return false;
  }
  PngErrorSink sink;
  const bool encoded = encodePng(file, rgb.pixels.data(), rgb.width, rgb.height, sink);
  // A full disk often shows only at the flush.
  const bool flushed = std::fflush(file) == 0 && !std::ferror(file);
  const int flush_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (encoded && flushed && closed) return true;
  error = path + ": " + (!encoded ? (sink.message[0] ? sink.message : "PNG encoding failed")
                                  : std::strerror(flushed ? errno : flush_errno));
  return false;
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
