// Shared set-up for the GPU suites: one headless EGL context for the whole
// process (contexts are expensive on llvmpipe), a calibrated test camera, and
// helpers to compare GPU output with the CPU reference in src/ibl.
#pragma once

#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"

namespace probelight::test {

// The process-wide context, created on first use; null (with the reason in
// `error`) when this machine has no usable EGL.
inline gles::EglContext* sharedContext(std::string& error) {
  static std::string creation_error;
  static std::unique_ptr<gles::EglContext> context = gles::EglContext::createHeadless(creation_error);
  error = creation_error;
  return context.get();
}

inline const gles::Capabilities& sharedCapabilities() {
  static const gles::Capabilities capabilities = gles::probeCapabilities();
  return capabilities;
}

class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string error;
    context_ = sharedContext(error);
    ASSERT_NE(context_, nullptr) << error;
    ASSERT_TRUE(context_->makeCurrent(error)) << error;
  }
  gles::EglContext* context_ = nullptr;
};

// A 640x480 camera with distortion strong enough that ignoring it would move
// the image by several pixels near the edges.
inline CameraIntrinsics testCamera() {
  CameraIntrinsics camera;
  camera.width_px = 640;
  camera.height_px = 480;
  camera.fx_px = 530.0;
  camera.fy_px = 527.0;
  camera.cx_px = 322.3;
  camera.cy_px = 236.8;
  camera.distortion = {-0.12, 0.06, 0.0012, -0.0008, -0.01};
  return camera;
}

// Camera at eye_w looking at target_w with world +Z up (camera y down).
inline PoseCamFromWorld lookAt(const glm::dvec3& eye_w, const glm::dvec3& target_w) {
  const glm::dvec3 forward = glm::normalize(target_w - eye_w);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(0.0, 0.0, 1.0)));
  const glm::dvec3 down = glm::cross(forward, right);
  PoseCamFromWorld pose;
  pose.R_cam_from_world = glm::transpose(glm::dmat3(right, down, forward));
  pose.t_cam_from_world = -(pose.R_cam_from_world * eye_w);
  return pose;
}

// Smooth analytic environment (linear camera units) with a warm "window"
// lobe, so maps have structure in every direction and no symmetry that would
// hide a flipped axis or a swapped face.
inline glm::dvec3 analyticEnvironment(const glm::dvec3& direction) {
  const glm::dvec3 d = glm::normalize(direction);
  const double window = std::pow(std::max(0.0, glm::dot(d, glm::normalize(glm::dvec3(0.6, 0.3, 0.74)))), 6.0);
  return {0.10 + 0.25 * (0.5 + 0.5 * d.z) + 0.55 * window, 0.18 + 0.12 * (0.5 + 0.5 * d.x) + 0.35 * window,
          0.22 + 0.18 * (0.5 + 0.5 * d.y) * (0.5 + 0.5 * d.z) + 0.15 * window};
}

inline bool allFinite(const ibl::CubeMapRGB& cube) {
  for (const auto& face : cube.faces) {
    for (const glm::vec3& texel : face) {
      if (!std::isfinite(texel.r) || !std::isfinite(texel.g) || !std::isfinite(texel.b)) return false;
    }
  }
  return true;
}

// d(linear) / d(encoded) of the sRGB curve at `encoded`: converts an error in
// encoded units (1/255 per 8-bit step) into linear units.
inline double srgbDecodeSlope(double encoded) {
  if (encoded <= 0.04045) return 1.0 / 12.92;
  return 2.4 / 1.055 * std::pow((encoded + 0.055) / 1.055, 1.4);
}

}  // namespace probelight::test
