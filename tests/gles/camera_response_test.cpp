// The object leaves its shader in the camera's own encoding
// (shaders-gles/camera_response.glsl, passes/camera_response.hpp): the
// frame's bytes and the object's then mean the same light, whichever
// transfer camera_transfer names.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "glowing_box.hpp"
#include "ibl/camera_projection.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/model_renderer.hpp"
#include "passes/object_compositor.hpp"

namespace probelight {
namespace {

using test::GpuTest;

// A flat object at linear 0.2 reads sRGB code 124, a 1.8 gamma's 104,
// linear 51; 8-bit rounding and the shader's float arithmetic keep it
// within a code.
struct TransferCase {
  ibl::CameraTransfer transfer;
  double expected_code;
};
const TransferCase kTransferCases[] = {{{ibl::CameraTransfer::Curve::kSrgb, 2.2}, 255.0 * ibl::linearToSrgb(0.2)},
                                       {{ibl::CameraTransfer::Curve::kGamma, 1.8}, 255.0 * std::pow(0.2, 1.0 / 1.8)},
                                       {{ibl::CameraTransfer::Curve::kLinear, 2.2}, 255.0 * 0.2}};

// The pixel where the object's centre (0, 0, 0.03) projects, per channel.
void expectObjectCentreCodes(const gles::RenderTarget& target, const CameraIntrinsics& camera,
                             const PoseCamFromWorld& pose, const glm::dvec3& expected_code, const std::string& what) {
  std::string error;
  ImageRGB8 result;
  ASSERT_TRUE(target.readRGB(result, error)) << error;
  const glm::dvec2 centre = ibl::projectToPixel(camera, pose.toCamera({0.0, 0.0, 0.03}));
  const std::uint8_t* pixel = result.row(static_cast<int>(centre.y)) + 3 * static_cast<int>(centre.x);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(pixel[c], expected_code[c], 1.0) << what << " channel " << c;
}

void expectObjectCentreCode(const gles::RenderTarget& target, const CameraIntrinsics& camera,
                            const PoseCamFromWorld& pose, const TransferCase& test_case) {
  expectObjectCentreCodes(target, camera, pose, glm::dvec3(test_case.expected_code),
                          "transfer " + std::to_string(static_cast<int>(test_case.transfer.curve)));
}

TEST_F(GpuTest, ASphereLeavesInTheCamerasTransfer) {
  const CameraIntrinsics camera = test::testCamera();
  const PoseCamFromWorld pose = test::lookAt({0.0, -0.30, 0.20}, {0.0, 0.0, 0.03});
  for (const TransferCase& test_case : kTransferCases) {
    const gles::Capabilities& caps = test::sharedCapabilities();
    std::string error;
    gles::RenderTarget target;
    passes::CameraFrameTexture frame;
    passes::EnvironmentMaps maps;
    passes::ObjectCompositor compositor;
    passes::ObjectCompositorSettings settings;
    settings.camera_transfer = test_case.transfer;
    ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
    ASSERT_TRUE(frame.init(caps, error)) << error;
    ASSERT_TRUE(maps.init(caps, {}, error)) << error;
    ASSERT_TRUE(compositor.init(caps, settings, maps.storage(), error)) << error;
    ImageRGB8 black;
    black.resize(camera.width_px, camera.height_px);
    ASSERT_TRUE(frame.upload(black, error)) << error;
    ibl::SurfaceMaterial flat;
    flat.ambient = 1.0f;
    flat.k_diffuse = 0.0f;
    ibl::SceneLighting lighting;
    lighting.ambient_rgb = glm::vec3(0.2f);
    target.bind();
    compositor.drawCameraBackground(frame);
    ASSERT_TRUE(compositor.drawSphereObject(camera, pose, {0.0, 0.0, 0.03}, 0.03, flat, lighting, maps, error))
        << error;
    expectObjectCentreCode(target, camera, pose, test_case);
  }
}

TEST_F(GpuTest, AModelLeavesInTheCamerasTransfer) {
  const CameraIntrinsics camera = test::testCamera();
  const PoseCamFromWorld pose = test::lookAt({0.09, -0.25, 0.19}, {0.0, 0.0, 0.03});
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(test::initBlackMaps(maps, caps, error)) << error;
  gles::RenderTarget target;
  ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
  for (const TransferCase& test_case : kTransferCases) {
    passes::ModelRenderer renderer;
    passes::ModelRendererSettings settings;
    settings.camera_transfer = test_case.transfer;
    ASSERT_TRUE(renderer.init(caps, maps.storage(), test::glowingBox(glm::vec3(0.2f)), test::glowingBoxPlacement(),
                              settings, error))
        << error;
    target.bind();
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    ASSERT_TRUE(renderer.draw(camera, pose, ibl::SceneLighting{}, maps, error)) << error;
    expectObjectCentreCode(target, camera, pose, test_case);
  }
}

// Auto exposure two stops down and a white balance move since the maps
// (stages/frame_response.hpp): the object's linear light is multiplied by
// the per-channel gain before the transfer. A flat object at linear 0.2
// then reads the sRGB code of 0.2 x gain in each channel, within a code.
TEST_F(GpuTest, TheObjectLeavesWithTheResponseGain) {
  const CameraIntrinsics camera = test::testCamera();
  const glm::vec3 gain(0.25f * 1.3f, 0.25f, 0.25f * 0.8f);
  glm::dvec3 expected;
  for (int c = 0; c < 3; ++c) expected[c] = 255.0 * ibl::linearToSrgb(0.2 * gain[c]);
  const gles::Capabilities& caps = test::sharedCapabilities();
  std::string error;
  passes::EnvironmentMaps maps;
  ASSERT_TRUE(test::initBlackMaps(maps, caps, error)) << error;
  gles::RenderTarget target;
  ASSERT_TRUE(target.init(camera.width_px, camera.height_px, error)) << error;
  target.bind();
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);

  const PoseCamFromWorld sphere_pose = test::lookAt({0.0, -0.30, 0.20}, {0.0, 0.0, 0.03});
  passes::ObjectCompositor compositor;
  ASSERT_TRUE(compositor.init(caps, {}, maps.storage(), error)) << error;
  compositor.setResponseGain(gain);
  ibl::SurfaceMaterial flat;
  flat.ambient = 1.0f;
  flat.k_diffuse = 0.0f;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = glm::vec3(0.2f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  ASSERT_TRUE(compositor.drawSphereObject(camera, sphere_pose, {0.0, 0.0, 0.03}, 0.03, flat, lighting, maps, error))
      << error;
  expectObjectCentreCodes(target, camera, sphere_pose, expected, "sphere");

  const PoseCamFromWorld model_pose = test::lookAt({0.09, -0.25, 0.19}, {0.0, 0.0, 0.03});
  passes::ModelRenderer renderer;
  ASSERT_TRUE(renderer.init(caps, maps.storage(), test::glowingBox(glm::vec3(0.2f)), test::glowingBoxPlacement(), {},
                            error))
      << error;
  renderer.setResponseGain(gain);
  target.bind();
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  ASSERT_TRUE(renderer.draw(camera, model_pose, ibl::SceneLighting{}, maps, error)) << error;
  expectObjectCentreCodes(target, camera, model_pose, expected, "model");
}

}  // namespace
}  // namespace probelight
