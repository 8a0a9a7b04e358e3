#include "capture/libcamera_log_levels.hpp"

#include <unistd.h>

#include <cstdlib>

namespace probelight {

std::string libcameraLogLevels(const char* current, const std::string& fallback, bool dma_buf_provider_usable) {
  std::string levels = current ? std::string(current) : fallback;
  // A setting that names the category itself is the user's to keep.
  if (dma_buf_provider_usable || levels.find("DmaBufAllocator") != std::string::npos) return levels;
  return levels.empty() ? "DmaBufAllocator:FATAL" : "DmaBufAllocator:FATAL," + levels;
}

bool dmaBufProviderUsable() {
  // libcamera 0.4's list (src/libcamera/dma_buf_allocator.cpp), in its order.
  for (const char* path : {"/dev/dma_heap/linux,cma", "/dev/dma_heap/reserved", "/dev/dma_heap/system", "/dev/udmabuf"})
    if (::access(path, R_OK | W_OK) == 0) return true;
  return false;
}

void setLibcameraLogLevels(const std::string& fallback) {
  const std::string levels = libcameraLogLevels(std::getenv("LIBCAMERA_LOG_LEVELS"), fallback, dmaBufProviderUsable());
  if (!levels.empty()) ::setenv("LIBCAMERA_LOG_LEVELS", levels.c_str(), 1);
}

}  // namespace probelight
