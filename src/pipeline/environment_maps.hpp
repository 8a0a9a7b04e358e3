// Stages 2 and 3: the mirror ball's image to a reflection cube map, and that
// map blurred on the sphere into a diffuse cube map. GPU versions of
// ibl::probeImageToCubeMap and two ibl::sphericalBlurPass passes (east, then
// north), checked against them in tests/gles.
//
// Storage (chosen at init from the capabilities):
//   kLinearHalfFloat  RGBA half floats, rgb = linear camera units.
//   kSrgb8            RGBA8, rgb = linearToSrgb(clamp(linear / linear_scale, 0, 1)).
//                     linear_scale is the largest value the map can hold:
//                     1 / probe_reflectance for camera-derived maps (an 8-bit
//                     camera cannot produce more), max(1, brightest texel) for
//                     setReflection(); the diffuse map inherits the reflection
//                     map's scale (a blur cannot exceed its input).
// In both, alpha is validity: 1 where the ball shows the direction, 0 in the
// blind spot behind the ball (where rgb is 0, as on the CPU); the diffuse
// map's alpha is the blurred validity (the fraction of its footprint seen).
// Cube maps are NEAREST-filtered; shaders filter bilinearly themselves on
// decoded values (cube_storage.glsl), so no float-linear extension is needed.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"
#include "pipeline/camera_frame_texture.hpp"

namespace probelight::pipeline {

struct EnvironmentMapSettings {
  int reflection_face_size = 64;    // seed A: a 640x480 frame rarely shows the ball above 64 px
  int intermediate_face_size = 32;  // after the east pass
  int diffuse_face_size = 32;
  int normal_iterations = 4;  // unrolled in the shader; ibl::ProbeToCubeParams::normal_iterations
  double blur_sigma_rad = 0.6;  // about a cosine lobe (SEEDS: three.js PMREM)
  int blur_half_taps = 8;
};

enum class CubeStorage { kLinearHalfFloat, kSrgb8 };

// A cube map on the GPU with how to decode it.
struct GpuCubeMap {
  gles::Texture texture;
  int face_size = 0;
  float linear_scale = 1.0f;  // kSrgb8 only (see above); 1 for half floats
};

class EnvironmentMaps {
 public:
  bool init(const gles::Capabilities& capabilities, const EnvironmentMapSettings& settings, std::string& error);

  // Stage 2. Renders the six reflection faces from the camera frame. Leaves
  // the framebuffer binding and viewport as it found them.
  bool updateReflection(const CameraFrameTexture& camera_frame, const ibl::MirrorBallView& view,
                        double probe_reflectance, std::string& error);
  // Uploads a CPU map as the reflection map (static environments, tests).
  bool setReflection(const ibl::CubeMapRGB& reflection, std::string& error);
  // Stage 3: east pass into the intermediate map, north pass into the diffuse map.
  bool updateDiffuse(std::string& error);

  // Read back in linear units (8-bit path decoded). `validity`, when given,
  // receives alpha laid out like CubeMapRGB::faces (face-major, row-major).
  std::optional<ibl::CubeMapRGB> readReflection(std::string& error, std::vector<float>* validity = nullptr) const;
  std::optional<ibl::CubeMapRGB> readIntermediate(std::string& error, std::vector<float>* validity = nullptr) const;
  std::optional<ibl::CubeMapRGB> readDiffuse(std::string& error, std::vector<float>* validity = nullptr) const;

  GLuint reflectionCube() const { return reflection_.texture.id(); }
  GLuint diffuseCube() const { return diffuse_.texture.id(); }
  const GpuCubeMap& reflection() const { return reflection_; }
  const GpuCubeMap& diffuse() const { return diffuse_; }
  CubeStorage storage() const { return storage_; }
  // E.g. "half float" or "8-bit sRGB (half float unavailable: ...)".
  const std::string& storageDescription() const { return storage_description_; }
  const EnvironmentMapSettings& settings() const { return settings_; }

 private:
  bool allocate(GpuCubeMap& map, int face_size, std::string& error) const;
  bool blurPass(const GpuCubeMap& input, GpuCubeMap& output, bool north, std::string& error);
  std::optional<ibl::CubeMapRGB> readCube(const GpuCubeMap& map, std::string& error, std::vector<float>* validity) const;

  EnvironmentMapSettings settings_;
  CubeStorage storage_ = CubeStorage::kSrgb8;
  std::string storage_description_;
  gles::Program probe_program_;
  gles::Program blur_program_;
  gles::FullScreenQuad quad_;
  gles::Framebuffer framebuffer_;
  GpuCubeMap reflection_;
  GpuCubeMap intermediate_;
  GpuCubeMap diffuse_;
};

// GLSL #define lines selecting a storage's encoding in cube_storage.glsl.
std::string cubeStorageDefines(CubeStorage storage);

}  // namespace probelight::pipeline
