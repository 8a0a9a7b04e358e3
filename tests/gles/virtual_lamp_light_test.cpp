// The virtual lamp's passes (passes/virtual_lamp_light) against the CPU's
// model (ibl/virtual_lamp): a frame of a flat floor whose pixels step
// through every 8-bit code (so sRGB's linear toe is met from both sides:
// a dark code the lamp lifts past it, a code the gain takes into it), a
// lamp above it, for each camera transfer. Every ground pixel must be its
// code decoded, times 1 + the lamp's ratio at the ground point its centre
// sees (ibl::lampToRoomRatio, through ibl::pixelToCameraRay), encoded:
// within a code (the 8-bit output's rounding, half a code, and the camera
// ray interpolated between the grid's vertices, a fraction of a pixel).
// With the exposure gain, the same times the gain. Pixels above the
// horizon keep their code times the gain.
//
// Then the whole-frame pass with the dome's shadow folded in against the
// ground shadow's own composite (GroundShadow::drawOnCameraImage over the
// background), with the lamp at intensity 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/virtual_lamp.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/ground_shadow.hpp"
#include "passes/object_compositor.hpp"
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
  // Each pixel's code: every code along a row, in runs of 3 columns (the
  // checked pixels are every third), the channels apart.
  auto codeAt = [](int x, int y, int c) { return static_cast<std::uint8_t>((x / 3 + 5 * y + 85 * c) % 256); };
  ImageRGB8 ramp;
  ramp.resize(camera.width_px, camera.height_px);
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x)
      for (int c = 0; c < 3; ++c) ramp.row(y)[3 * x + c] = codeAt(x, y, c);
  ASSERT_TRUE(background.upload(ramp, error)) << error;
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
    double worst = 0.0, largest_ratio = 0.0;
    int ground = 0, sky = 0, toe = 0;
    const glm::dmat3 world_from_cam = glm::transpose(pose.R_cam_from_world);
    for (int y = 0; y < camera.height_px; y += 3)
      for (int x = 0; x < camera.width_px; x += 3) {
        const glm::dvec3 ray = world_from_cam * ibl::pixelToCameraRay(camera, {x, y});
        glm::dvec3 expected_linear;
        for (int c = 0; c < 3; ++c) {
          expected_linear[c] = gain * ibl::decodeCameraValue(transfer, codeAt(x, y, c) / 255.0);
          toe += codeAt(x, y, c) <= 10;  // sRGB's toe: codes up to 0.04045 x 255
        }
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
    std::printf("transfer %d, gain %.1f: %d ground and %d sky pixels (%d values in the toe), largest ratio %.2f, "
                "worst %.2f codes\n",
                GetParam(), gain, ground, sky, toe, largest_ratio, worst);
    ASSERT_GT(ground, 1000);
    ASSERT_GT(sky, 100);
    ASSERT_GT(toe, 1000);
    EXPECT_GT(largest_ratio, 0.3);
    EXPECT_LT(worst, 1.0);
  }
}

// sRGB, a gamma of 2.2, linear.
INSTANTIATE_TEST_SUITE_P(Transfers, VirtualLampPass, ::testing::Values(0, 1, 2));

// The lamp's draws stand in for the background's and the ground shadow's:
// with the lamp at intensity 0, the whole-frame and detail passes over a
// frame of every code must give what the background and the shadow's own
// composite give (a sphere under a low and an overhead light: long and
// short shadows). The shadow's composite multiplies where its cells reach
// and the lamp's pass reads the same fraction texture everywhere in the
// square (1 outside the cells): a code for the two draws' rounding of the
// same product, through the lens's rays against the square's grid.
TEST_F(GpuTest, VirtualLampPassesGiveTheGroundShadowsCompositeWithoutTheLamp) {
  const CameraIntrinsics camera = sim::defaultScene().camera;
  const PoseCamFromWorld pose = test::lookAt({0.05, -0.4, 0.35}, {0.0, 0.0, 0.0});
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  gles::RenderTarget target_fb;
  passes::CameraFrameTexture background;
  passes::ObjectCompositor compositor;
  passes::GroundShadow shadow;
  passes::VirtualLampLight light;
  ASSERT_TRUE(target_fb.init(camera.width_px, camera.height_px, error)) << error;
  ASSERT_TRUE(background.init(caps, error)) << error;
  ASSERT_TRUE(compositor.init(caps, {}, passes::CubeStorage::kSrgb8, error)) << error;
  ASSERT_TRUE(shadow.init(caps, {}, error)) << error;
  ASSERT_TRUE(light.init(caps, {}, camera, error)) << error;
  ImageRGB8 frame_image;
  frame_image.resize(camera.width_px, camera.height_px);
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x)
      for (int c = 0; c < 3; ++c) frame_image.row(y)[3 * x + c] = static_cast<std::uint8_t>((x + 3 * y + 85 * c) % 256);
  ASSERT_TRUE(background.upload(frame_image, error)) << error;
  ibl::ShadowLight overhead, low;
  overhead.direction_w = {0.0, 0.0, 1.0};
  overhead.share_rgb = glm::dvec3(0.4, 0.45, 0.5);
  low.direction_w = glm::normalize(glm::dvec3(0.8, 0.3, 0.5));
  low.share_rgb = glm::dvec3(0.3);
  ibl::ShadowCaster sphere;
  sphere.radius_m = 0.035;
  ASSERT_TRUE(shadow.update({overhead, low}, sphere, error)) << error;
  ASSERT_TRUE(shadow.hasShadow());
  ibl::VirtualLamp lamp;
  lamp.intensity = 0.0;
  ASSERT_TRUE(light.updateShadow(lamp, passes::casterTriangles(sphere), error)) << error;
  RigGeometry no_rig;  // the ball far away, out of view
  no_rig.probe_center_w = {0.0, 50.0, 1.0};
  no_rig.probe_radius_m = 0.01;
  for (const double gain : {1.0, 0.7}) {
    ImageRGB8 expected, out;
    target_fb.bind();
    compositor.drawCameraBackground(background, gain);
    ASSERT_TRUE(shadow.drawOnCameraImage(camera, pose, background, error, gain)) << error;
    ASSERT_TRUE(target_fb.readRGB(expected, error)) << error;
    passes::VirtualLampLight::Frame frame;
    frame.ratio_at_one_metre_rgb = ibl::lampRatioAtOneMetre(lamp, glm::dvec3(1.0));
    frame.dome_shadow = &shadow;
    frame.exposure_gain = gain;
    target_fb.bind();
    ASSERT_TRUE(light.drawSmooth(camera, pose, background, no_rig, frame, error)) << error;
    ASSERT_TRUE(light.drawDetail(camera, pose, background, no_rig, frame, error)) << error;
    ASSERT_TRUE(target_fb.readRGB(out, error)) << error;
    int worst = 0, darkened = 0;
    for (std::size_t i = 0; i < out.pixels.size(); ++i) {
      worst = std::max(worst, std::abs(int{out.pixels[i]} - int{expected.pixels[i]}));
      // Where the shadow takes 5% or more of the frame's light.
      const double background_code = 255.0 * ibl::linearToSrgb(gain * ibl::srgbToLinear(frame_image.pixels[i] / 255.0));
      darkened += expected.pixels[i] < 0.95 * background_code - 1.0;
    }
    std::printf("gain %.1f: %d values darkened by the shadow; the lamp's passes within %d codes of the shadow's composite\n",
                gain, darkened, worst);
    EXPECT_GT(darkened, 2000);
    EXPECT_LE(worst, 1);
  }
}

}  // namespace
}  // namespace probelight
