// The displays' saved frames, written as PNG files off the render thread
// (core/write_queue.hpp), and their names.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/types.hpp"
#include "core/write_queue.hpp"

namespace probelight {

using ImageWriteQueue = WriteQueue<ImageRGB8>;

// A queue that writes each frame with writeRgbPng (OpenCV's PNG writer
// would cost more than a frame).
std::unique_ptr<ImageWriteQueue> makePngWriteQueue();

// "<prefix>_NNNNNN.png" for frame `number` (frame_, snapshot_, camera_).
std::string numberedPngName(const std::string& prefix, std::uint64_t number);

}  // namespace probelight
