#include "capture/camera_list.hpp"

#include <algorithm>
#include <cstring>
#include <memory>

#include <libcamera/camera_manager.h>
#include <libcamera/property_ids.h>

#include "capture/libcamera_adapter.hpp"

namespace probelight {

namespace {

std::string locationName(std::int32_t location) {
  switch (location) {
    case libcamera::properties::CameraLocationFront:
      return "front";
    case libcamera::properties::CameraLocationBack:
      return "back";
    case libcamera::properties::CameraLocationExternal:
      return "external";
    default:
      return "";
  }
}

std::string sizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

}  // namespace

std::optional<std::vector<CameraListing>> listLibcameraCameras(std::string& error) {
  auto manager = std::make_unique<libcamera::CameraManager>();
  if (const int result = manager->start(); result != 0) {
    error = std::string("libcamera's camera manager did not start: ") + std::strerror(-result);
    return std::nullopt;
  }
  std::vector<CameraListing> listings;
  for (const std::shared_ptr<libcamera::Camera>& camera : manager->cameras()) {
    CameraListing listing;
    listing.id = camera->id();
    const libcamera::ControlList& properties = camera->properties();
    if (const auto model = properties.get(libcamera::properties::Model)) listing.model = *model;
    if (const auto location = properties.get(libcamera::properties::Location)) listing.location = locationName(*location);
    // The viewfinder stream's formats, as run asks for it. A camera in use
    // by another program still lists them (generateConfiguration does not
    // need it acquired).
    if (std::unique_ptr<libcamera::CameraConfiguration> config = libcamera_adapter::viewfinderConfiguration(*camera);
        config && config->size() == 1) {
      const libcamera::StreamFormats& formats = config->at(0).formats();
      for (const libcamera::PixelFormat& pixel_format : formats.pixelformats()) {
        CameraStreamFormat format;
        format.pixel_format = pixel_format.toString();
        const libcamera::SizeRange range = formats.range(pixel_format);
        format.range = {static_cast<int>(range.min.width), static_cast<int>(range.min.height),
                        static_cast<int>(range.max.width), static_cast<int>(range.max.height),
                        static_cast<int>(range.hStep), static_cast<int>(range.vStep)};
        // A range with steps is the camera's own (vimc's, a Pi's ISP):
        // StreamFormats::sizes() would list common sizes that fit it, which
        // the camera may still round (vimc: 640x480 to 636x480). Listed
        // sizes, and a bound of them, come with steps of 0.
        const bool camera_range = range.min != range.max && (range.hStep != 0 || range.vStep != 0);
        if (!camera_range)
          for (const libcamera::Size& size : formats.sizes(pixel_format))
            format.sizes_px.emplace_back(static_cast<int>(size.width), static_cast<int>(size.height));
        listing.formats.push_back(std::move(format));
      }
    }
    listings.push_back(std::move(listing));
  }
  manager->stop();
  return listings;
}

std::string formatCameraList(const std::vector<CameraListing>& cameras, std::size_t max_sizes_shown) {
  if (cameras.empty())
    return "cameras: libcamera found no camera (a USB webcam: plugged in and in `lsusb`, its /dev/video* "
           "readable by this user, group video; the board's camera: its ribbon cable and camera_auto_detect=1); "
           "without one, run --source sim or --source images\n";
  std::string text = std::to_string(cameras.size()) + (cameras.size() == 1 ? " camera:\n" : " cameras:\n");
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const CameraListing& camera = cameras[i];
    text += std::to_string(i) + ": " + (camera.model.empty() ? std::string("(no model given)") : "'" + camera.model + "'");
    if (!camera.location.empty()) text += ", " + camera.location;
    text += "\n   id: " + camera.id + "\n";
    if (camera.formats.empty()) {
      text += "   no viewfinder stream offered\n";
      continue;
    }
    for (const CameraStreamFormat& format : camera.formats) {
      std::string line = "   " + format.pixel_format + ":";
      std::vector<std::pair<int, int>> sizes = format.sizes_px;
      std::sort(sizes.begin(), sizes.end(),
                [](const auto& a, const auto& b) { return a.first * a.second < b.first * b.second; });
      if (sizes.empty()) {
        // Appended piece by piece: GCC 12's -Wrestrict misreads
        // `" " + std::string(...)` inlined here (a false alarm, GCC bug 105329).
        line += ' ';
        line += sizeText(format.range.min_width_px, format.range.min_height_px);
        line += " to ";
        line += sizeText(format.range.max_width_px, format.range.max_height_px);
        if (format.range.width_step_px > 1 || format.range.height_step_px > 1) {
          line += ", in steps of ";
          line += sizeText(format.range.width_step_px, format.range.height_step_px);
        }
        line += " (the camera may round a size; run says the nearest it takes)";
      } else {
        // The smallest ones and the largest: the largest is what a user
        // looks for, the smallest what runs fastest.
        const std::size_t shown = std::max<std::size_t>(max_sizes_shown, 2);
        for (std::size_t k = 0; k < sizes.size(); ++k) {
          if (sizes.size() > shown && k == shown - 1) {
            line += " ...";
            k = sizes.size() - 1;
          }
          line += ' ';
          line += sizeText(sizes[k].first, sizes[k].second);
        }
      }
      text += line + "\n";
    }
  }
  text += "Pick one with --camera-id ID or camera.id in probelight.yaml (default: the first).\n";
  return text;
}

}  // namespace probelight
