#include "app/list_cameras.hpp"

#include "capture/camera_list.hpp"
#include "capture/libcamera_log_levels.hpp"
#include "core/log_priority.hpp"

namespace probelight {

int runListCameras(const CamerasOptions&, std::ostream& out, std::ostream& err) {
  // libcamera's own INFO and WARN lines (its version, a missing IPA) would
  // come before the listing on every call; a user's LIBCAMERA_LOG_LEVELS
  // still wins. Read when its logger starts, so before the manager does.
  setLibcameraLogLevels("*:ERROR");
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
