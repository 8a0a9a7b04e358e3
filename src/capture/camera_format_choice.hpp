// Which of a camera's formats and sizes probelight streams (issue 17). Real
// cameras differ: the Pi's give YUV420 or NV12, USB webcams YUYV or MJPEG,
// the kernel's vimc test camera only packed RGB. The source asks for one it
// can convert on the GPU, in order of bytes a pixel (the planar Y'CbCr
// layouts also give tag detection a Y' plane to read in place); MJPEG,
// decoded on the CPU, comes last. The size must be camera.yaml's: its
// intrinsics hold for that size only.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "capture/frame_source.hpp"

namespace probelight {

enum class CameraFormat { kYuv420, kNv12, kYuyv, kBgr888, kRgb888, kXrgb8888, kMjpeg };

struct CameraFormatInfo {
  CameraFormat format;
  const char* config_name;     // probelight.yaml's camera.pixel_format
  const char* libcamera_name;  // libcamera's PixelFormat::toString()
  // How its frames reach the GPU; MJPEG is decoded to kRgb8 first.
  PixelLayout layout;
};

// Every format probelight takes, in the order `auto` prefers them.
const std::vector<CameraFormatInfo>& cameraFormats();
const CameraFormatInfo& cameraFormatInfo(CameraFormat format);
// "auto", then each config name, for probelight.yaml's check.
std::vector<std::string> cameraFormatConfigNames();

// `wanted` is a config name or "auto"; `offered` the libcamera names the
// camera lists. The chosen format, or nullopt with `error` naming what was
// wanted and what the camera offers.
std::optional<CameraFormat> chooseCameraFormat(const std::vector<std::string>& offered, const std::string& wanted,
                                               const std::string& camera_name, std::string& error);

struct FrameSizePx {
  int width = 0;
  int height = 0;
  bool operator==(const FrameSizePx& other) const { return width == other.width && height == other.height; }
};

// The sizes a camera streams a format at: a list, or a range with steps
// (libcamera's StreamFormats gives either or both).
struct OfferedSizes {
  std::vector<FrameSizePx> listed;
  std::optional<FrameSizePx> range_min, range_max;
  int width_step = 1, height_step = 1;
};

// The offered size nearest `wanted` (the smallest sum of the width's and
// the height's relative differences; a range is snapped to its steps),
// or nullopt when nothing is offered.
std::optional<FrameSizePx> nearestOfferedSize(const OfferedSizes& offered, FrameSizePx wanted);

// Empty when `chosen` is camera.yaml's size; else the one line that says so,
// naming both and what to do.
std::string sizeMismatchProblem(const std::string& camera_name, const char* format_name, FrameSizePx wanted,
                                FrameSizePx chosen);

}  // namespace probelight
