// The libcamera API differences between Debian bookworm's 0.0.3 and
// Raspberry Pi OS's 0.3-0.5, in one place (selected by libcamera/version.h).
#pragma once

#include <memory>
#include <vector>

#include <libcamera/camera.h>
#include <libcamera/stream.h>
#include <libcamera/version.h>

namespace probelight::libcamera_adapter {

// generateConfiguration takes a std::vector<StreamRole> in 0.0.x and a
// Span<const StreamRole> from 0.1 on; a vector converts to both.
inline std::unique_ptr<libcamera::CameraConfiguration> viewfinderConfiguration(libcamera::Camera& camera) {
  const std::vector<libcamera::StreamRole> roles{libcamera::StreamRole::Viewfinder};
  return camera.generateConfiguration(roles);
}

// The file descriptor of a frame buffer plane: a SharedFD in every version
// since 0.0.1 (it was a plain FileDescriptor before).
template <typename Plane>
int planeFd(const Plane& plane) {
  return plane.fd.get();
}

}  // namespace probelight::libcamera_adapter
