// camera.yaml: the camera's intrinsics, in the layout OpenCV's calibration
// tools write (image_width, image_height, camera_matrix, distortion_coefficients),
// and optionally the lens position they hold at (lens_position_dioptres).
#pragma once

#include <optional>
#include <string>

#include "config/config_reader.hpp"
#include "core/types.hpp"

namespace probelight::config {

// Reads camera.yaml. Accepts distortion_coefficients as 1x4, 1x5, 4x1 or 5x1
// (longer rational/thin-prism vectors only when their extra terms are zero)
// and ignores the bookkeeping keys OpenCV's calibration samples add
// (calibration_time, nr_of_frames, avg_reprojection_error, ...). Any other key
// is an error. Throws ConfigError.
CameraIntrinsics loadCameraFile(const std::string& path);

// Writes camera.yaml in the same layout (distortion as 1x5). Throws
// ConfigError when `camera` would not load back or the file cannot be written.
void saveCameraFile(const std::string& path, const CameraIntrinsics& camera);

// Plausibility bounds (validateCameraIntrinsics says why each); the image
// sides' is probelight::kMaxImageSidePx (core/types.hpp).
constexpr double kMinFocalPerSide = 0.1;   // x the image's larger side
constexpr double kMaxFocalPerSide = 50.0;
constexpr double kMaxDistortion[5] = {100.0, 100.0, 1.0, 1.0, 1000.0};  // |k1| |k2| |p1| |p2| |k3|

// Where the radial distortion's map from undistorted to distorted radius
// stops rising before it reaches the frame's farthest corner (normalised
// radius, undistorted), or nullopt when it rises all the way: past a fold
// two directions land on one pixel. Tangential terms are left out (|p| <= 1
// and, from real calibrations, below 0.01: they tilt the map, not fold it).
std::optional<double> radialFoldInsideImage(const CameraIntrinsics& camera);

// The checks loadCameraFile applies, for intrinsics that come from elsewhere
// (the simulator, a calibration run). Throws ConfigError naming `path`.
void validateCameraIntrinsics(const CameraIntrinsics& camera, const std::string& path);

}  // namespace probelight::config
