#include "capture/rgb_image_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>

#include <libdeflate.h>

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
std::vector<std::uint8_t> encodePng(const std::uint8_t* pixels, int width, int height) {
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
  const std::vector<std::uint8_t> bytes = encodePng(rgb.pixels.data(), rgb.width, rgb.height);
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

namespace {

struct ImageSize {
  std::uint64_t width = 0, height = 0;
};

std::uint32_t bigEndian32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return static_cast<std::uint32_t>(b[at]) << 24 | static_cast<std::uint32_t>(b[at + 1]) << 16 |
         static_cast<std::uint32_t>(b[at + 2]) << 8 | b[at + 3];
}
std::uint16_t bigEndian16(const std::vector<std::uint8_t>& b, std::size_t at) {
  return static_cast<std::uint16_t>(b[at] << 8 | b[at + 1]);
}
std::int32_t littleEndian32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(b[at]) | static_cast<std::uint32_t>(b[at + 1]) << 8 |
                                   static_cast<std::uint32_t>(b[at + 2]) << 16 |
                                   static_cast<std::uint32_t>(b[at + 3]) << 24);
}

bool startsWith(const std::vector<std::uint8_t>& bytes, const char* magic, std::size_t length) {
  return bytes.size() >= length && std::memcmp(bytes.data(), magic, length) == 0;
}

// A PNG's size from its IHDR chunk, and whether its IEND chunk is there
// (within the last 4 KiB: a few tools append bytes after it).
std::string checkPng(const std::vector<std::uint8_t>& bytes, ImageSize& size) {
  if (bytes.size() < 24 || std::memcmp(bytes.data() + 12, "IHDR", 4) != 0) return "a PNG without its IHDR header";
  size = {bigEndian32(bytes, 16), bigEndian32(bytes, 20)};
  const std::size_t from = bytes.size() > 4096 ? bytes.size() - 4096 : 24;
  static const std::uint8_t kIend[4] = {'I', 'E', 'N', 'D'};
  if (std::search(bytes.begin() + static_cast<std::ptrdiff_t>(from), bytes.end(), kIend, kIend + 4) == bytes.end())
    return "a PNG cut short (no IEND chunk at its end)";
  return "";
}

// A JPEG's size from its first frame header (SOF), found by walking the
// marker segments; then an end-of-image marker must follow the scan. Inside
// entropy-coded data 0xFF is always followed by 0x00 or a restart marker,
// so 0xFF 0xD9 after the first scan can only be the end (an EXIF thumbnail's
// own end marker comes before the scan).
std::string checkJpeg(const std::vector<std::uint8_t>& bytes, ImageSize& size) {
  std::size_t at = 2;
  bool have_size = false;
  while (at + 4 <= bytes.size()) {
    if (bytes[at] != 0xFF) return "a JPEG whose marker segments are broken";
    const std::uint8_t marker = bytes[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {
      at += 2;
      continue;
    }
    const std::size_t length = bigEndian16(bytes, at + 2);
    if (length < 2 || at + 2 + length > bytes.size()) return "a JPEG cut short (inside its headers)";
    const bool frame_header = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame_header && !have_size) {
      if (length < 7) return "a JPEG with a broken frame header";
      size = {bigEndian16(bytes, at + 7), bigEndian16(bytes, at + 5)};
      have_size = true;
    }
    if (marker == 0xDA) {  // start of scan: the entropy-coded data follows
      if (!have_size) return "a JPEG without a frame header";
      static const std::uint8_t kEnd[2] = {0xFF, 0xD9};
      if (std::search(bytes.begin() + static_cast<std::ptrdiff_t>(at + 2 + length), bytes.end(), kEnd, kEnd + 2) ==
          bytes.end())
        return "a JPEG cut short (no end-of-image marker after its scan)";
      return "";
    }
    at += 2 + length;
  }
  return "a JPEG cut short (no scan)";
}

// Netpbm (P1-P6): the width and height are the first two numbers after the
// magic, with # comments allowed between.
void pnmSize(const std::vector<std::uint8_t>& bytes, ImageSize& size) {
  std::uint64_t numbers[2] = {0, 0};
  std::size_t at = 2;
  for (std::uint64_t& number : numbers) {
    // As OpenCV's reader: everything up to the next digit is skipped (a
    // '#' comment to the end of its line), and the byte that ends a number
    // is consumed whatever it is. Headers "P6 3533<DLE>266777" and
    // "P6 3533#266777" made OpenCV allocate 2.8 GB where a stricter parse
    // here read 3533x0 (found by fuzz/image_file_fuzzer.cpp). Where OpenCV
    // would refuse a separator, reading on can only refuse more.
    while (at < bytes.size() && !std::isdigit(bytes[at])) {
      if (bytes[at] == '#')
        while (at < bytes.size() && bytes[at] != '\n') ++at;
      else
        ++at;
    }
    // Saturate: 20 digits of a hostile header must not wrap.
    while (at < bytes.size() && std::isdigit(bytes[at])) {
      number = std::min<std::uint64_t>(number * 10 + (bytes[at] - '0'), 1ull << 40);
      ++at;
    }
    ++at;  // the byte that ended the number
  }
  size = {numbers[0], numbers[1]};
}

// Why these bytes are not an image to decode, or "".
std::string checkImageBytes(const std::vector<std::uint8_t>& bytes) {
  ImageSize size;
  std::string problem;
  if (startsWith(bytes, "\x89PNG\r\n\x1a\n", 8))
    problem = checkPng(bytes, size);
  else if (startsWith(bytes, "\xFF\xD8", 2))
    problem = checkJpeg(bytes, size);
  else if (startsWith(bytes, "BM", 2) && bytes.size() >= 26) {
    const std::int64_t width = littleEndian32(bytes, 18), height = littleEndian32(bytes, 22);
    size = {static_cast<std::uint64_t>(width < 0 ? -width : width),
            static_cast<std::uint64_t>(height < 0 ? -height : height)};
  } else if (bytes.size() >= 3 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6' && std::isspace(bytes[2])) {
    pnmSize(bytes, size);
  } else {
    // Only the formats whose header is checked here reach OpenCV: its other
    // decoders are not ours to harden, and one aborts the process (a damaged
    // DICOM file trips an assert in GDCM; found by fuzz/image_file_fuzzer.cpp).
    return "not a PNG, JPEG, BMP or PNM image (the formats probelight reads frames from)";
  }
  if (!problem.empty()) return problem;
  if (size.width > static_cast<std::uint64_t>(kMaxImageSidePx) || size.height > static_cast<std::uint64_t>(kMaxImageSidePx))
    return "its header says " + std::to_string(size.width) + "x" + std::to_string(size.height) +
           ", above the " + std::to_string(kMaxImageSidePx) + " px limit on a side";
  return "";
}

// Reads the whole of `path` into `bytes`; false with `why` when it cannot.
// Opened without blocking and checked again on the open descriptor, so a
// FIFO swapped in after the first check cannot hang the read either.
bool readWholeFile(const std::string& path, std::vector<std::uint8_t>& bytes, std::string& why) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    why = errno == ENOENT ? "no such file" : std::strerror(errno);
    return false;
  }
  if (!S_ISREG(info.st_mode)) {
    why = S_ISDIR(info.st_mode) ? "a folder, not an image file" : "not a regular file (a FIFO, socket or device)";
    return false;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    why = std::strerror(errno);
    return false;
  }
  bool ok = ::fstat(fd, &info) == 0 && S_ISREG(info.st_mode);
  if (!ok) why = "not a regular file (a FIFO, socket or device)";
  if (ok && static_cast<std::uint64_t>(info.st_size) > kMaxImageFileBytes) {
    why = "larger than " + std::to_string(kMaxImageFileBytes >> 20) + " MiB";
    ok = false;
  }
  if (ok) {
    try {
      bytes.resize(static_cast<std::size_t>(info.st_size));
    } catch (const std::bad_alloc&) {
      why = "does not fit in memory";
      ok = false;
    }
  }
  std::size_t done = 0;
  while (ok && done < bytes.size()) {
    const ssize_t got = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      why = got < 0 ? std::strerror(errno) : "shorter than its size (changed while read)";
      ok = false;
      break;
    }
    done += static_cast<std::size_t>(got);
  }
  ::close(fd);
  return ok;
}

}  // namespace

cv::Mat readImageFile(const std::string& path, int imread_flags, std::string* why) {
  std::string problem;
  std::vector<std::uint8_t> bytes;
  cv::Mat image;
  if (readWholeFile(path, bytes, problem)) {
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
