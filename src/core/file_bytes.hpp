// Bytes from files that users hand us: read whole and safely, and, for
// images, checked before any decoder sees them. No decoding here (core has
// no OpenCV): capture/rgb_image_io.hpp decodes frames, model/ a model's
// textures.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace probelight {

// Reads the whole of `path` into `bytes`; false, with `why` (one phrase, no
// path), when it does not exist, is not a regular file (a FIFO would block
// the read forever, a folder or device is no file to read), is larger than
// `max_bytes`, or cannot be read. Opened without blocking and checked again
// on the open descriptor, so a FIFO swapped in after the first check cannot
// hang the read either.
bool readWholeFile(const std::string& path, std::uint64_t max_bytes, std::vector<std::uint8_t>& bytes,
                   std::string& why);

// Why `bytes` are not an image to hand a decoder, or "": not a PNG, JPEG,
// BMP or PNM file (by its first bytes; other decoders are not checked here,
// and a damaged DICOM file aborts OpenCV's); a header claiming a side above
// kMaxImageSidePx (refused before anything is decoded, where OpenCV would
// decode a 20000x20000 PNG of 1 MB into 1.2 GB first); a PNG or JPEG cut
// short (no IEND chunk, no end-of-image marker after the scan), which
// OpenCV decodes with the missing rows grey and only a libjpeg warning.
std::string checkImageBytes(const std::vector<std::uint8_t>& bytes);

}  // namespace probelight
