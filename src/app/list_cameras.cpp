#include "app/list_cameras.hpp"

#include <cstdlib>
#include <filesystem>

#include "capture/camera_list.hpp"
#include "core/log_priority.hpp"

namespace probelight {

int runListCameras(const CamerasOptions&, std::ostream& out, std::ostream& err) {
  // libcamera's own INFO and WARN lines (its version, a missing IPA) would
  // come before the listing on every call; a user's LIBCAMERA_LOG_LEVELS
  // still wins. Read when its logger starts, so before the manager does.
  // libcamera 0.4 and later also log "Could not open any dma-buf provider"
  // as an ERROR where the machine has neither /dev/dma_heap nor
  // /dev/udmabuf (a laptop, a VM); the listing needs neither, so there that
  // category keeps only its fatal messages. It comes first: libcamera 0.4
  // takes the first pattern that matches a category.
  std::error_code ignored;
  const bool dma_buf_provider =
      std::filesystem::exists("/dev/dma_heap", ignored) || std::filesystem::exists("/dev/udmabuf", ignored);
  ::setenv("LIBCAMERA_LOG_LEVELS", dma_buf_provider ? "*:ERROR" : "DmaBufAllocator:FATAL,*:ERROR", 0);
  std::string error;
  const auto cameras = listLibcameraCameras(error);
  if (!cameras) {
    err << logPrefix(LogPriority::kError) << "probelight: cameras: " << error << "\n";
    return 1;
  }
  out << formatCameraList(*cameras);
  return 0;
}

}  // namespace probelight
