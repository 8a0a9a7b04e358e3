// RGB8 images (probelight's byte order) to and from OpenCV's BGR8, and to
// image files: the one place the channel order is swapped.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/types.hpp"

namespace probelight {

// `bgr` (CV_8UC3) into `rgb`, resized (its storage reused where it fits).
void rgbFromBgr(const cv::Mat& bgr, ImageRGB8& rgb);
ImageRGB8 rgbFromBgr(const cv::Mat& bgr);
// A BGR copy of `rgb`, as OpenCV's drawing and imwrite take it.
cv::Mat bgrFromRgb(const ImageRGB8& rgb);
// `rgb` written to `path` (the format from its extension; `params` as
// cv::imwrite's). False when it cannot be written.
bool writeRgbImage(const std::string& path, const ImageRGB8& rgb, const std::vector<int>& params = {});
// `rgb` written to `path` as a PNG, fast: every row with the Up filter,
// deflated by libdeflate at level 1 in one call. Camera frames are noisy,
// so LZ matching finds little, and OpenCV's writer (every filter tried on
// every row, then zlib) costs more than a frame; libpng with zlib's
// run-length strategy was about 2.5x faster than that, and libdeflate is
// about 2x faster again for files about 15% larger (a 640x480 demo frame:
// 7.7 ms and 428 KB against 14.4 ms and 372 KB). False, with `error` saying
// why, when the file cannot be written. pixels_per_metre > 0: the file
// says its physical size (a pHYs chunk), so a print at 100% is to scale.
bool writeRgbPng(const std::string& path, const ImageRGB8& rgb, std::string& error, double pixels_per_metre = 0.0);
// The largest image file read (a full-size 8192x8192 16-bit PNG is smaller).
constexpr std::uint64_t kMaxImageFileBytes = 1ull << 30;

// cv::imread made safe for files from users. Empty, with `why` saying why
// (one phrase, no path), when `path`:
// - does not exist, or is not a regular file (a FIFO would block the read
//   forever, a folder or device is no image);
// - is larger than kMaxImageFileBytes;
// - is not a PNG, JPEG, BMP or PNM file (by its first bytes): OpenCV's other
//   decoders are not checked here, and a damaged DICOM file aborts one;
// - has a header (PNG, JPEG, BMP, PNM) claiming a side above
//   kMaxImageSidePx: refused before anything is decoded, where OpenCV would
//   decode a 20000x20000 PNG of 1 MB into 1.2 GB first;
// - is a PNG or JPEG cut short (no IEND chunk, no end-of-image marker after
//   the scan), which OpenCV decodes with the missing rows grey and only a
//   libjpeg warning;
// - cannot be decoded (OpenCV throws instead of returning an empty image
//   when a header claims more pixels than it allows).
cv::Mat readImageFile(const std::string& path, int imread_flags, std::string* why = nullptr);

}  // namespace probelight
