// What the frame went through on its way out of the camera, applied to the
// virtual object, which the shaders render in linear light
// (shaders-gles/camera_response.glsl): the camera's transfer, and noise of
// the frame's own statistic (ibl/sensor_noise.hpp), so the object is not
// cleaner than the video around it (Klein & Murray, "Compositing for small
// cameras", 2008).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "gles/gl_objects.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/sensor_noise.hpp"

namespace probelight::passes {

// The noise an object program adds this frame.
struct SensorNoiseMatch {
  ibl::AddedNoiseModel model;
  std::uint64_t frame_index = 0;  // moves the noise pattern from frame to frame
};

// camera_transfer.glsl's and camera_response.glsl's defines.
std::string cameraTransferDefines(const ibl::CameraTransfer& transfer);
std::string cameraResponseDefines(const ibl::CameraTransfer& transfer, bool match_noise);

// The bloom's bright pass (passes/object_bloom.hpp): an object program
// built with these after cameraResponseDefines writes its light beyond
// white, sqrt((light - 1) / kBloomRange), instead of its colour.
constexpr double kBloomRange = 16.0;
std::string bloomBrightPassDefines();

// The noise samples: kSizePx^2 RGBA texels, each channel an independent
// N(0, 1) value stored as round-down(128 + 32 z) (clamped to the byte: |z|
// under 4), which decodes as (code - 127.5) / 32, z to the nearest 1/32
// centred on its step: unbiased. Fixed seed: the same texture every run.
class SensorNoiseTexture {
 public:
  static constexpr int kSizePx = 128;
  bool init(std::string& error);
  GLuint id() const { return texture_.id(); }
  bool valid() const { return texture_.valid(); }

 private:
  gles::Texture texture_;
};
std::vector<std::uint8_t> standardNormalTexels(int size_px, std::uint32_t seed);

// The texture offset (whole texels, in texture units) for a frame: a
// scramble of the index, so consecutive frames' patterns are unrelated.
glm::vec2 noiseOffsetForFrame(std::uint64_t frame_index, int size_px);

// u_camera_gamma for a gamma transfer, u_response_gain_rgb (the exposure
// and white balance now over the object's light's: camera_response.glsl's
// cameraOutput); with `noise`, its texture on `unit` and its uniforms.
// `program` must be in use and built with cameraResponseDefines(transfer,
// noise != nullptr).
void setCameraResponseUniforms(const gles::Program& program, const ibl::CameraTransfer& transfer,
                               const glm::vec3& response_gain_rgb, const SensorNoiseMatch* noise,
                               const SensorNoiseTexture& texture, int unit);

}  // namespace probelight::passes
