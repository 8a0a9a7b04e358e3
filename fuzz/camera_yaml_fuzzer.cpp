// camera.yaml (config::loadCameraFile): any bytes give intrinsics within the
// documented bounds, or one ConfigError line naming the file.
#include <algorithm>

#include "config/camera_file.hpp"
#include "fuzz/fuzz_input.hpp"

using namespace probelight;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz::writeInput(data, size, "camera.yaml");
  try {
    const CameraIntrinsics camera = config::loadCameraFile(path);
    fuzz::require(camera.width_px >= 1 && camera.width_px <= kMaxImageSidePx && camera.height_px >= 1 &&
                      camera.height_px <= kMaxImageSidePx,
                  "an image size out of 1..8192 accepted");
    const double side = std::max(camera.width_px, camera.height_px);
    for (const double focal : {camera.fx_px, camera.fy_px})
      fuzz::require(fuzz::finite(focal) && focal >= config::kMinFocalPerSide * side &&
                        focal <= config::kMaxFocalPerSide * side,
                    "a focal length out of its bounds accepted");
    fuzz::require(fuzz::finite(camera.cx_px) && fuzz::finite(camera.cy_px), "a non-finite principal point accepted");
    for (std::size_t i = 0; i < camera.distortion.size(); ++i)
      fuzz::require(fuzz::finite(camera.distortion[i]) && std::abs(camera.distortion[i]) <= config::kMaxDistortion[i],
                    "a distortion coefficient out of its bounds accepted");
  } catch (const config::ConfigError& error) {
    fuzz::requireOneLineNaming(error.what(), path);
  }
  return 0;
}
