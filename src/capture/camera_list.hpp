// What `probelight cameras` lists: each camera libcamera finds, with what its
// viewfinder stream (the one run streams) offers. listLibcameraCameras asks
// libcamera; formatCameraList is the text, pure, so it is tested without a
// camera.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace probelight {

struct CameraSizeRange {
  int min_width_px = 0, min_height_px = 0, max_width_px = 0, max_height_px = 0;
  int width_step_px = 0, height_step_px = 0;  // 0: not a range the camera gave (a bound of its sizes)
};

struct CameraStreamFormat {
  std::string pixel_format;  // libcamera's name: YUYV, MJPEG, NV12, RGB888, ...
  // The sizes the camera lists (a webcam's, from uvcvideo); empty when it
  // gives a range instead, whose common sizes libcamera would only guess at.
  std::vector<std::pair<int, int>> sizes_px;
  CameraSizeRange range;  // the span of sizes it takes
};

struct CameraListing {
  std::string id;        // libcamera's id: --camera-id, camera.id
  std::string model;     // properties::Model ("" if it does not say)
  std::string location;  // "front", "back", "external" ("" if it does not say)
  std::vector<CameraStreamFormat> formats;
};

// Every camera libcamera finds; nullopt with `error` when its camera
// manager does not start. Starts and stops a CameraManager (one per
// process at a time: not while a camera is streaming).
std::optional<std::vector<CameraListing>> listLibcameraCameras(std::string& error);

// The listing as text: a line per camera (its index, model, id, location),
// then a line per pixel format with its sizes (at most `max_sizes_shown`:
// the smallest, "...", the largest; or its range and steps when the camera
// gives a range). No
// camera: one line saying so, what to check, and the sources that need
// none.
std::string formatCameraList(const std::vector<CameraListing>& cameras, std::size_t max_sizes_shown = 8);

}  // namespace probelight
