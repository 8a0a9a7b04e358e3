// Shared set-up for the accuracy suites: one headless EGL context per suite,
// and the static views of the simulated rig they measure from.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gles/egl_context.hpp"
#include "sim/scene_config.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight::testing {

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

}  // namespace probelight::testing
