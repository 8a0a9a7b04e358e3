#include "core/file_bytes.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <new>

#include "core/types.hpp"

namespace probelight {
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

}  // namespace

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

bool readWholeFile(const std::string& path, std::uint64_t max_bytes, std::vector<std::uint8_t>& bytes, std::string& why) {
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
  if (ok && static_cast<std::uint64_t>(info.st_size) > max_bytes) {
    why = "larger than " + std::to_string(max_bytes >> 20) + " MiB";
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


}  // namespace probelight
