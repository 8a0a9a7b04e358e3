// The virtual lamp's passes (passes/virtual_lamp_light) against the CPU's
// model (ibl/virtual_lamp): a uniform grey frame of a flat floor, a lamp
// above it, for each camera transfer. Every ground pixel must be the grey
// decoded, times 1 + the lamp's ratio at the ground point its centre sees
// (ibl::lampToRoomRatio, through ibl::pixelToCameraRay), encoded: within
// a code (the 8-bit output's rounding, half a code, and the camera ray
// interpolated between the grid's vertices, a fraction of a pixel). With
// the exposure gain, the same times the gain. Pixels above the horizon
// keep the grey times the gain.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/virtual_lamp.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/virtual_lamp_light.hpp"
#include "sim/scene_config.hpp"

namespace probelight {
namespace {

using test::GpuTest;

double encodeValue(const ibl::CameraTransfer& transfer, double linear) {
  // The inverse of decodeCameraValue, by bisection (it rises).
  double low = 0.0, high = 1.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (low + high);
    (ibl::decodeCameraValue(transfer, mid) < linear ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

class VirtualLampPass : public GpuTest, public ::testing::WithParamInterface<int> {};

TEST_P(VirtualLampPass, GivesEachGroundPixelTheLampsRatioInLinearLight) {
  ibl::CameraTransfer transfer;
  transfer.curve = GetParam() == 0 ? ibl::CameraTransfer::Curve::kSrgb
                   : GetParam() == 1 ? ibl::CameraTransfer::Curve::kGamma
                                     : ibl::CameraTransfer::Curve::kLinear;
  CameraIntrinsics camera = sim::defaultScene().camera;  // with its lens distortion
  // A low camera looking far across the floor: its top rows see past the
  // horizon, so both kinds of pixel are checked.
  const glm::dvec3 eye(0.0, -0.5, 0.2), target(0.0, 0.3, 0.0);
  const PoseCamFromWorld pose = test::lookAt(eye, target);
  ibl::VirtualLamp lamp;
  lamp.position_w = {0.05, 0.0, 0.15};
  lamp.colour = {1.0, 0.8, 0.6};
  lamp.intensity = 0.01;
  const glm::dvec3 room(1.0, 1.0, 1.0);
  const glm::dvec3 ratio_1m = ibl::lampRatioAtOneMetre(lamp, room);
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  gles::RenderTarget target_fb;
  passes::CameraFrameTexture background;
  passes::VirtualLampLight light;
  ASSERT_TRUE(target_fb.init(camera.width_px, camera.height_px, error)) << error;
  ASSERT_TRUE(background.init(caps, error)) << error;
  passes::VirtualLampLightSettings settings;
  settings.camera_transfer = transfer;
  ASSERT_TRUE(light.init(caps, settings, camera, error)) << error;
  constexpr std::uint8_t kGrey = 90;
  ImageRGB8 grey;
  grey.resize(camera.width_px, camera.height_px);
  std::fill(grey.pixels.begin(), grey.pixels.end(), kGrey);
  ASSERT_TRUE(background.upload(grey, error)) << error;
  ASSERT_TRUE(light.updateShadow(lamp, {}, error)) << error;  // no object: no shadow
  RigGeometry no_rig;  // the ball far away, out of view
  no_rig.probe_center_w = {0.0, 50.0, 1.0};
  no_rig.probe_radius_m = 0.01;
  for (const double gain : {1.0, 0.6}) {
    passes::VirtualLampLight::Frame frame;
    frame.ratio_at_one_metre_rgb = ratio_1m;
    frame.exposure_gain = gain;
    target_fb.bind();
    ASSERT_TRUE(light.drawSmooth(camera, pose, background, no_rig, frame, error)) << error;
    ASSERT_TRUE(light.drawDetail(camera, pose, background, no_rig, frame, error)) << error;
    ImageRGB8 out;
    ASSERT_TRUE(target_fb.readRGB(out, error)) << error;
    const double grey_linear = ibl::decodeCameraValue(transfer, kGrey / 255.0);
    double worst = 0.0, largest_ratio = 0.0;
    int ground = 0, sky = 0;
    const glm::dmat3 world_from_cam = glm::transpose(pose.R_cam_from_world);
    for (int y = 0; y < camera.height_px; y += 3)
      for (int x = 0; x < camera.width_px; x += 3) {
        const glm::dvec3 ray = world_from_cam * ibl::pixelToCameraRay(camera, {x, y});
        glm::dvec3 expected_linear(grey_linear * gain);
        if (ray.z < 0.0) {
          const glm::dvec3 at = eye + (-eye.z / ray.z) * ray;
          const glm::dvec3 ratio = ibl::lampToRoomRatio(lamp, room, glm::dvec2(at));
          expected_linear *= 1.0 + ratio;
          largest_ratio = std::max(largest_ratio, ratio.g);
          ++ground;
        } else {
          ++sky;
        }
        for (int c = 0; c < 3; ++c) {
          const double expected = 255.0 * encodeValue(transfer, std::min(expected_linear[c], 1.0));
          worst = std::max(worst, std::abs(out.row(y)[3 * x + c] - expected));
        }
      }
    std::printf("transfer %d, gain %.1f: %d ground and %d sky pixels, largest ratio %.2f, worst %.2f codes\n",
                GetParam(), gain, ground, sky, largest_ratio, worst);
    ASSERT_GT(ground, 1000);
    ASSERT_GT(sky, 100);
    EXPECT_GT(largest_ratio, 0.3);
    EXPECT_LT(worst, 1.0);
  }
}

// sRGB, a gamma of 2.2, linear.
INSTANTIATE_TEST_SUITE_P(Transfers, VirtualLampPass, ::testing::Values(0, 1, 2));

}  // namespace
}  // namespace probelight
