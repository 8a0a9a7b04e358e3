#include "capture/rgb_image_io.hpp"

#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <memory>
#include <new>

#include <libdeflate.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/file_bytes.hpp"

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

void appendBigEndian32(std::vector<std::uint8_t>& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(value >> shift));
}

// A chunk's CRC-32 covers its type and data (PNG specification, 5.3).
void appendChunkCrc(std::vector<std::uint8_t>& out, std::size_t type_at) {
  appendBigEndian32(out, static_cast<std::uint32_t>(libdeflate_crc32(0, out.data() + type_at, out.size() - type_at)));
}

struct CompressorDeleter {
  void operator()(libdeflate_compressor* compressor) const { libdeflate_free_compressor(compressor); }
};

// The whole file in memory: 8-bit RGB, every row with the Up filter (the
// one that helps most on camera frames), and the filtered rows deflated in
// one call into a single IDAT chunk. Empty when the compressor cannot be
// allocated.
std::vector<std::uint8_t> encodePng(const std::uint8_t* pixels, int width, int height, double pixels_per_metre) {
  // One compressor per writing thread, kept: allocating it costs more than
  // a small frame's compression.
  thread_local std::unique_ptr<libdeflate_compressor, CompressorDeleter> compressor(libdeflate_alloc_compressor(1));
  if (!compressor) return {};
  const std::size_t stride = static_cast<std::size_t>(width) * 3;
  std::vector<std::uint8_t> filtered((stride + 1) * static_cast<std::size_t>(height));
  constexpr std::uint8_t kFilterUp = 2;
  for (int y = 0; y < height; ++y) {
    std::uint8_t* out = &filtered[(stride + 1) * static_cast<std::size_t>(y)];
    const std::uint8_t* row = pixels + stride * static_cast<std::size_t>(y);
    out[0] = kFilterUp;
    if (y == 0) {
      std::memcpy(out + 1, row, stride);  // the row above the first is zero
    } else {
      const std::uint8_t* above = row - stride;
      for (std::size_t i = 0; i < stride; ++i) out[1 + i] = static_cast<std::uint8_t>(row[i] - above[i]);
    }
  }
  const std::size_t bound = libdeflate_zlib_compress_bound(compressor.get(), filtered.size());
  std::vector<std::uint8_t> file{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  file.reserve(8 + 25 + 12 + bound + 12);
  appendBigEndian32(file, 13);
  std::size_t type_at = file.size();
  file.insert(file.end(), {'I', 'H', 'D', 'R'});
  appendBigEndian32(file, static_cast<std::uint32_t>(width));
  appendBigEndian32(file, static_cast<std::uint32_t>(height));
  // Bit depth 8, colour type 2 (RGB), compression 0, filter method 0, no interlace.
  file.insert(file.end(), {8, 2, 0, 0, 0});
  appendChunkCrc(file, type_at);
  if (pixels_per_metre > 0.0) {
    // pHYs: the physical size a viewer or printer shows it at (unit 1: metre).
    const auto per_metre = static_cast<std::uint32_t>(std::lround(pixels_per_metre));
    appendBigEndian32(file, 9);
    type_at = file.size();
    file.insert(file.end(), {'p', 'H', 'Y', 's'});
    appendBigEndian32(file, per_metre);
    appendBigEndian32(file, per_metre);
    file.push_back(1);
    appendChunkCrc(file, type_at);
  }
  const std::size_t length_at = file.size();
  appendBigEndian32(file, 0);  // IDAT length, known once compressed
  type_at = file.size();
  file.insert(file.end(), {'I', 'D', 'A', 'T'});
  const std::size_t data_at = file.size();
  file.resize(data_at + bound);
  const std::size_t compressed =
      libdeflate_zlib_compress(compressor.get(), filtered.data(), filtered.size(), file.data() + data_at, bound);
  if (compressed == 0) return {};
  file.resize(data_at + compressed);
  for (int k = 0; k < 4; ++k) file[length_at + k] = static_cast<std::uint8_t>(compressed >> (24 - 8 * k));
  appendChunkCrc(file, type_at);
  appendBigEndian32(file, 0);
  type_at = file.size();
  file.insert(file.end(), {'I', 'E', 'N', 'D'});
  appendChunkCrc(file, type_at);
  return file;
}

}  // namespace

bool writeRgbPng(const std::string& path, const ImageRGB8& rgb, std::string& error, double pixels_per_metre) {
  if (rgb.width <= 0 || rgb.height <= 0 || rgb.pixels.size() < static_cast<std::size_t>(rgb.width) * rgb.height * 3) {
    error = path + ": no image to write";
    return false;
  }
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) {
    error = path + ": " + std::strerror(errno);
    return false;
  }
  const std::vector<std::uint8_t> bytes = encodePng(rgb.pixels.data(), rgb.width, rgb.height, pixels_per_metre);
  const bool written = !bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
  const int write_errno = errno;
  // A full disk often shows only at the flush.
  const bool flushed = written && std::fflush(file) == 0 && !std::ferror(file);
  const int flush_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (written && flushed && closed) return true;
  error = path + ": " + (bytes.empty() ? std::string("PNG encoding failed (libdeflate)")
                         : !written    ? std::strerror(write_errno)
                         : !flushed    ? std::strerror(flush_errno)
                                       : std::strerror(errno));
  return false;
}

cv::Mat readImageFile(const std::string& path, int imread_flags, std::string* why) {
  std::string problem;
  std::vector<std::uint8_t> bytes;
  cv::Mat image;
  if (readWholeFile(path, kMaxImageFileBytes, bytes, problem)) {
    if (bytes.empty()) problem = "an empty file";
    if (problem.empty()) problem = checkImageBytes(bytes);
    if (problem.empty()) {
      try {
        image = cv::imdecode(bytes, imread_flags);
      } catch (const cv::Exception&) {
        image = cv::Mat();
      } catch (const std::bad_alloc&) {
        image = cv::Mat();  // a header within OpenCV's limit that still does not fit in memory
      }
      if (image.empty()) problem = "not an image OpenCV can decode";
    }
  }
  if (!problem.empty()) {
    if (why) *why = problem;
    return cv::Mat();
  }
  return image;
}

}  // namespace probelight
