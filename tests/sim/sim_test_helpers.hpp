// Small helpers shared by the simulator's tests.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/types.hpp"
#include "sim/scene_config.hpp"

namespace probelight::sim::testing {

inline double srgbDecode(double code) {
  double v = code / 255.0;
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

inline double pixelLinear(const ImageRGB8& image, int x, int y, int channel) {
  return srgbDecode(image.row(y)[x * 3 + channel]);
}

// Small and fast: for tests that do not need the full 640x480 frame.
inline SceneConfig smallScene() {
  SceneConfig scene = defaultScene();
  scene.camera.width_px = 160;
  scene.camera.height_px = 120;
  scene.camera.fx_px = 150.0;
  scene.camera.fy_px = 150.0;
  scene.camera.cx_px = 79.5;
  scene.camera.cy_px = 59.5;
  return scene;
}

}  // namespace probelight::sim::testing
