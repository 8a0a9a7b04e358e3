// The headless display's frames, written as PNG files off the render
// thread (core/write_queue.hpp).
#pragma once

#include "core/types.hpp"
#include "core/write_queue.hpp"

namespace probelight {

using ImageWriteQueue = WriteQueue<ImageRGB8>;

}  // namespace probelight
