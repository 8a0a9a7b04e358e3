// Shared set-up for the accuracy suites: one headless EGL context per suite,
// and the static views of the simulated rig they measure from.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/types.hpp"
#include "gles/egl_context.hpp"
#include "ibl/probe_outline.hpp"
#include "sim/world.hpp"
#include "sim/scene_config.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight::testing {

// Rec. 709 luminance of linear RGB, the accuracy suites' measure.
inline double luminance(const glm::dvec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; }

// The default scene in `environment`, seen from a still camera at this
// distance, elevation and azimuth (looking at the rig's default point).
inline sim::SceneConfig staticView(const std::string& environment, double distance_m, double elevation_deg,
                                   double azimuth_deg) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.environment = environment;
  scene.camera_path.name = "static";
  scene.camera_path.distance_m = distance_m;
  scene.camera_path.elevation_deg = elevation_deg;
  scene.camera_path.azimuth_start_deg = azimuth_deg;
  return scene;
}

// The tag tracked in a rendered frame, as the kiosk's first frame tracks it.
inline tracking::TagTrackResult trackRendered(const sim::SceneConfig& scene, const ImageRGB8& frame) {
  std::vector<std::uint8_t> luma;
  lumaFromRgb(frame, luma);
  tracking::TagTracker tracker(tracking::TagDetectorSettings{}, scene.rig, scene.camera);
  return tracker.track(luma.data(), frame.width, frame.height, frame.width);
}

class GpuSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    context_ = gles::EglContext::createHeadless(error).release();
    ASSERT_NE(context_, nullptr) << error;
  }
  static void TearDownTestSuite() {
    delete context_;
    context_ = nullptr;
  }
  static inline gles::EglContext* context_ = nullptr;
};

// An exposure bracket of `frame`: the reference exposure, then shorter ones
// 3 stops apart until the ball's square shows no pixel at or above
// `clip_code` (or 15 stops down). images[i] was taken at evs[i].
inline void renderBracketUntilBallUnclipped(const sim::World& world, std::uint64_t frame, const ImageRGB8& reference,
                                            const ibl::ProbeOutline& outline, int clip_code,
                                            std::vector<ImageRGB8>& images, std::vector<double>& evs) {
  images.assign(1, reference);
  evs.assign(1, 0.0);
  auto ballClips = [&](const ImageRGB8& image) {
    const int r = static_cast<int>(outline.radius_px);
    for (int y = std::max(0, static_cast<int>(outline.center_px.y) - r);
         y <= std::min(image.height - 1, static_cast<int>(outline.center_px.y) + r); ++y)
      for (int x = std::max(0, static_cast<int>(outline.center_px.x) - r);
           x <= std::min(image.width - 1, static_cast<int>(outline.center_px.x) + r); ++x)
        for (int c = 0; c < 3; ++c)
          if (image.row(y)[3 * x + c] >= clip_code) return true;
    return false;
  };
  while (ballClips(images.back()) && evs.back() > -15.0) {
    evs.push_back(evs.back() - 3.0);
    ImageRGB8 shorter;
    FrameTruth ignored;
    world.render(frame, shorter, ignored, evs.back());
    images.push_back(std::move(shorter));
  }
}

}  // namespace probelight::testing
