#include "capture/camera_format_choice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace probelight {

const std::vector<CameraFormatInfo>& cameraFormats() {
  static const std::vector<CameraFormatInfo> formats = {
      {CameraFormat::kYuv420, "yuv420", "YUV420", PixelLayout::kI420},
      {CameraFormat::kNv12, "nv12", "NV12", PixelLayout::kNv12},
      {CameraFormat::kYuyv, "yuyv", "YUYV", PixelLayout::kYuyv},
      {CameraFormat::kBgr888, "bgr888", "BGR888", PixelLayout::kBgr888},
      {CameraFormat::kRgb888, "rgb888", "RGB888", PixelLayout::kRgb888},
      {CameraFormat::kXrgb8888, "xrgb8888", "XRGB8888", PixelLayout::kXrgb8888},
      {CameraFormat::kMjpeg, "mjpeg", "MJPEG", PixelLayout::kRgb8},
  };
  return formats;
}

const CameraFormatInfo& cameraFormatInfo(CameraFormat format) {
  for (const CameraFormatInfo& info : cameraFormats())
    if (info.format == format) return info;
  return cameraFormats().front();
}

std::vector<std::string> cameraFormatConfigNames() {
  std::vector<std::string> names = {"auto"};
  for (const CameraFormatInfo& info : cameraFormats()) names.push_back(info.config_name);
  return names;
}

std::optional<CameraFormat> chooseCameraFormat(const std::vector<std::string>& offered, const std::string& wanted,
                                               const std::string& camera_name, std::string& error) {
  auto isOffered = [&](const CameraFormatInfo& info) {
    return std::find(offered.begin(), offered.end(), info.libcamera_name) != offered.end();
  };
  std::string offered_list;
  for (const std::string& name : offered) offered_list += (offered_list.empty() ? "" : ", ") + name;
  if (offered_list.empty()) offered_list = "nothing";
  if (wanted == "auto") {
    for (const CameraFormatInfo& info : cameraFormats())
      if (isOffered(info)) return info.format;
    std::string known;
    for (const CameraFormatInfo& info : cameraFormats()) known += (known.empty() ? "" : ", ") + std::string(info.libcamera_name);
    error = "camera: " + camera_name + " offers " + offered_list + ", none of the formats probelight reads (" + known + ")";
    return std::nullopt;
  }
  for (const CameraFormatInfo& info : cameraFormats()) {
    if (wanted != info.config_name) continue;
    if (isOffered(info)) return info.format;
    error = "camera: " + camera_name + " does not offer " + info.libcamera_name + " (camera.pixel_format " + wanted +
            "); it offers " + offered_list + ": set camera.pixel_format to auto or to one of those";
    return std::nullopt;
  }
  error = "camera: unknown camera.pixel_format '" + wanted + "'";
  return std::nullopt;
}

std::optional<FrameSizePx> nearestOfferedSize(const OfferedSizes& offered, FrameSizePx wanted) {
  std::vector<FrameSizePx> candidates = offered.listed;
  if (offered.range_min && offered.range_max) {
    // The range's nearest point, snapped to its steps from its minimum.
    auto snap = [](int value, int low, int high, int step) {
      step = std::max(step, 1);
      const int clamped = std::clamp(value, low, std::max(low, high));
      const int steps = static_cast<int>(std::lround(static_cast<double>(clamped - low) / step));
      return std::min(low + steps * step, std::max(low, high));
    };
    candidates.push_back({snap(wanted.width, offered.range_min->width, offered.range_max->width, offered.width_step),
                          snap(wanted.height, offered.range_min->height, offered.range_max->height, offered.height_step)});
  }
  std::optional<FrameSizePx> best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const FrameSizePx& size : candidates) {
    if (size.width <= 0 || size.height <= 0) continue;
    const double distance = std::abs(std::log(static_cast<double>(size.width) / wanted.width)) +
                            std::abs(std::log(static_cast<double>(size.height) / wanted.height));
    if (distance < best_distance) {
      best_distance = distance;
      best = size;
    }
  }
  return best;
}

std::string sizeMismatchProblem(const std::string& camera_name, const char* format_name, FrameSizePx wanted,
                                FrameSizePx chosen) {
  if (chosen == wanted) return "";
  auto text = [](FrameSizePx size) { return std::to_string(size.width) + "x" + std::to_string(size.height); };
  return "camera: " + camera_name + " cannot stream " + format_name + " at camera.yaml's " + text(wanted) +
         "; the nearest it offers is " + text(chosen) + ": calibrate the camera at " + text(chosen) +
         " (probelight calibrate-camera) or use a camera.yaml made at a size it offers";
}

}  // namespace probelight
