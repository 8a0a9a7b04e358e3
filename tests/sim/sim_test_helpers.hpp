// Small helpers shared by the simulator's tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

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

// Area (px^2) and centroid (OpenCV pixel centres) of a coverage mask, as
// World::coverage returns it (row-major, `width` wide).
struct MaskMoments {
  double area_px = 0.0;
  glm::dvec2 centroid_px{0.0};
};

inline MaskMoments coverageMoments(const std::vector<float>& coverage, int width) {
  MaskMoments m;
  glm::dvec2 sum(0.0);
  for (size_t i = 0; i < coverage.size(); ++i) {
    const double f = coverage[i];
    m.area_px += f;
    sum += f * glm::dvec2(static_cast<double>(i % static_cast<size_t>(width)), static_cast<double>(i / static_cast<size_t>(width)));
  }
  m.centroid_px = sum / m.area_px;
  return m;
}

// The variance (px^2) of an edge's line spread along the rows: the green
// channel's linear light differenced along x over x0 - reach .. x0 +
// reach, its second moment about its mean, averaged over rows [y_begin,
// y_end) (a falling edge, bright on the left; rows with no fall skipped).
// -1 when no row has one.
inline double edgeSpreadVariance(const ImageRGB8& image, int x0, int reach, int y_begin, int y_end) {
  double total = 0.0;
  int rows = 0;
  for (int y = y_begin; y < y_end; ++y) {
    double weight = 0.0, first = 0.0, second = 0.0;
    for (int x = x0 - reach; x < x0 + reach; ++x) {
      const double step = pixelLinear(image, x, y, 1) - pixelLinear(image, x + 1, y, 1);
      const double at = x + 0.5;
      weight += step;
      first += step * at;
      second += step * at * at;
    }
    if (!(weight > 0.0)) continue;
    const double mean = first / weight;
    total += second / weight - mean * mean;
    ++rows;
  }
  return rows > 0 ? total / rows : -1.0;
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
