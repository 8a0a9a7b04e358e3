// Stages 2 and 3: the mirror ball's image to a reflection cube map, and that
// map integrated on the sphere into a diffuse cube map holding E(n) / pi.
// GPU versions of ibl::probeImageToCubeMap and
// ibl::irradianceOverPiByCosinePasses (prefilter, east cos^2 pass and north
// cos pass on latitude-longitude maps, normalised convolution of validity),
// checked against them in tests/gles.
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
// blind spot behind the ball (where rgb is 0, as on the CPU). The prefiltered
// and intermediate maps hold rgb premultiplied by (blurred) validity and
// alpha = that validity. The diffuse map's rgb is divided by it (normalised
// convolution: the blind spot is filled from what the ball saw nearby; rgb 0
// where alpha <= 1e-6) and its alpha stays the blurred validity: the
// cosine-weighted fraction of the normal's hemisphere the ball saw
// (coverage), not 1.
// Cube maps are NEAREST-filtered; shaders filter bilinearly themselves on
// decoded values (cube_storage.glsl), so no float-linear extension is needed.
//
// Two ways to make the diffuse map, same storage and convention (it holds
// E(n) / pi, read with the normal), so ObjectCompositor and readDiffuse do
// not care which made it:
//   updateDiffuse          ibl::irradianceOverPiByCosinePasses: prefilter
//                          (reflection_face_size -> prefilter_face_size),
//                          east pass (-> an intermediate_rows x
//                          2 intermediate_rows latitude-longitude map), north
//                          pass along its columns (-> a second one), and the
//                          resampling to the cube (-> diffuse_face_size);
//   updateDiffuseFromSH9   R&H's 9-coefficient irradiance. GLES2 has no
//                          compute shaders and no render-to-9-values
//                          reduction worth its passes, so the projection runs
//                          on the CPU: the caller does
//                            readReflection(error, &validity)
//                            -> ibl::projectToSH9(map, &validity)
//                            -> updateDiffuseFromSH9(sh, error)
//                          The read-back is 6 x 64^2 RGBA (98 KiB in 8 bits)
//                          and the projection 27 multiply-adds a texel; see
//                          tests/gles/sh9_and_blend_test.cpp for the times.
//
// Temporal blending (new_weight < 1): the new diffuse map is
//   new_weight * fresh + (1 - new_weight) * previous
// in linear light, alpha (validity) likewise. It is done in the final pass's
// shader from the previous map, which lives in a second (ping-pong) texture,
// not with glBlendColor / GL_CONSTANT_ALPHA: fixed-function blending of the
// 8-bit maps would mix sRGB-encoded bytes (for a doubling of the light at
// weight 0.3 that is off by 3.6-3.9% on average and up to 6.4% per texel,
// measured in tests/gles/sh9_and_blend_test.cpp) and could not follow
// a change of linear_scale between updates (it would mix values encoded on
// different scales). The cost is one more diffuse-sized cube map and one
// texel fetch per output texel. Because of the ping-pong, diffuseCube()
// alternates between two texture names: fetch it (or diffuse()) per frame.
// The first update after init is never blended (there is no previous map).
// In RGBA8 a repeated update at weight w stops within ~0.6 / w 8-bit levels
// of its target (a step smaller than half a level is rounded away): 2 levels
// at w = 0.3; any 8-bit IIR filter has this dead band.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/glossy_maps.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/spherical_blur.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "passes/camera_frame_texture.hpp"

namespace probelight::passes {

// The diffuse fields are ibl::CosineIrradianceSettings' (same defaults; see
// cosineIrradianceSettings below).
struct EnvironmentMapSettings {
  int reflection_face_size = 64;    // seed A: a 640x480 frame rarely shows the ball above 64 px
  int prefilter_face_size = 16;     // about the tap spacing; must divide reflection_face_size (factor <= 8)
  int intermediate_rows = 32;  // of the latitude-longitude maps after the east and north passes (even, 4..128)
  int diffuse_face_size = 16;
  int normal_iterations = 1;  // unrolled in the shader; ibl::ProbeToCubeParams::normal_iterations
  ibl::CameraTransfer camera_transfer;  // how the camera's values decode to linear light (sRGB by default)
  int blur_half_taps = 16;    // 2 * half_taps + 1 taps a pass, pi / (2 half_taps + 1) apart; 0..32

  // Glossy levels (updateGlossy; ibl::glossyMap, see src/ibl/glossy_maps.hpp
  // for why these): the reflection map convolved with cos^n lobes, sharpest
  // first. 0..2 levels; maps are allocated for the first glossy_levels.
  int glossy_levels = 2;
  std::array<double, 2> glossy_exponent{128.0, 16.0};  // n, >= 1
  // Output and prefilter size: must divide reflection_face_size (factor 1..8).
  std::array<int, 2> glossy_face_size{32, 16};
  std::array<int, 2> glossy_intermediate_face_size{64, 32};
  int glossy_half_taps = 8;  // 2 * half_taps + 1 taps a pass over [-3 sigma, 3 sigma]; 1..32
  double glossy_pole_direct_deg = 10.0;  // glossy north taps this close to +-Z integrate their east circle directly
};

// The CPU reference's settings for glossy level `level`.
ibl::GlossyLevelSettings glossyLevelSettings(const EnvironmentMapSettings& settings, int level);

// The CPU reference's settings for the same maps.
ibl::CosineIrradianceSettings cosineIrradianceSettings(const EnvironmentMapSettings& settings);

enum class CubeStorage { kLinearHalfFloat, kSrgb8 };

// A cube map on the GPU with how to decode it.
struct GpuCubeMap {
  gles::Texture texture;
  int face_size = 0;
  float linear_scale = 1.0f;  // kSrgb8 only (see above); 1 for half floats
};

// A latitude-longitude map (ibl::LatLongRGB's layout: row y at colatitude
// (y + 0.5) pi / rows) in a NEAREST-filtered 2D texture, same storage.
struct GpuLatLongMap {
  gles::Texture texture;
  int rows = 0;  // columns: 2 rows
  float linear_scale = 1.0f;
};

class EnvironmentMaps {
 public:
  bool init(const gles::Capabilities& capabilities, const EnvironmentMapSettings& settings, std::string& error);

  // Stage 2. Renders the six reflection faces from the camera frame. Leaves
  // the framebuffer binding and viewport as it found them.
  bool updateReflection(const CameraFrameTexture& camera_frame, const ibl::MirrorBallView& view,
                        double probe_reflectance, std::string& error);
  // Uploads a CPU map as the reflection map (static environments, tests).
  // `validity` (layout as read*'s) becomes alpha; without it alpha is 1.
  bool setReflection(const ibl::CubeMapRGB& reflection, std::string& error,
                     const std::vector<float>* validity = nullptr);
  // Stage 3: prefilter pass into the prefiltered map, east pass into the east
  // latitude-longitude map, north pass into the north one, and the
  // resampling (with the division by coverage) into the diffuse map.
  // new_weight in [0, 1]: the share of this update in the result (1: no
  // blending, the map is replaced; see above).
  bool updateDiffuse(std::string& error, float new_weight = 1.0f);
  // What the current diffuse map's values are multiplied by to be in the
  // next update's units (the camera's exposure and white balance moved
  // between their frames), for the blend; 1 until set.
  void setPreviousDiffuseUnits(const glm::vec3& previous_to_new) { previous_units_ = previous_to_new; }
  // Stage 3, SH9 alternative: renders max(0, E(n)) / pi from `sh` (see
  // ibl::sh9DiffuseMap) into the diffuse map, alpha 1, blended as above. In
  // the 8-bit storage the scale is max(1, the largest value stored).
  bool updateDiffuseFromSH9(const ibl::SH9RGB& sh, std::string& error, float new_weight = 1.0f);
  // Glossy levels from the current reflection map, each by three passes
  // (prefilter to glossy_face_size, east cos^(n+1) into the intermediate
  // map, north cos^n with the pole correction and the division by coverage).
  // Same storage rules as the diffuse map: rgb is the lobe's mean radiance
  // (normalised by validity), alpha the blurred validity, and in RGBA8 the
  // reflection map's linear_scale. Not blended over time (the reflection
  // map is not either). Only needed when a material's glossiness lies
  // strictly between 0 and 1 (ibl::needsGlossy); the app skips it otherwise.
  bool updateGlossy(std::string& error);

  // Read back in linear units (8-bit path decoded). `validity`, when given,
  // receives alpha laid out like CubeMapRGB::faces (face-major, row-major).
  std::optional<ibl::CubeMapRGB> readReflection(std::string& error, std::vector<float>* validity = nullptr) const;
  // The prefiltered map as stored: rgb premultiplied by alpha.
  std::optional<ibl::CubeMapRGB> readPrefiltered(std::string& error, std::vector<float>* validity = nullptr) const;
  std::optional<ibl::CubeMapRGB> readDiffuse(std::string& error, std::vector<float>* validity = nullptr) const;
  std::optional<ibl::CubeMapRGB> readGlossy(int level, std::string& error, std::vector<float>* validity = nullptr) const;

  GLuint reflectionCube() const { return reflection_.texture.id(); }
  GLuint diffuseCube() const { return diffuse_.texture.id(); }
  const GpuCubeMap& reflection() const { return reflection_; }
  const GpuCubeMap& diffuse() const { return diffuse_; }
  // Level 0..glossyLevels()-1, sharpest first; 0 for a level not configured.
  GLuint glossyCube(int level) const;
  const GpuCubeMap& glossy(int level) const { return glossy_[static_cast<size_t>(level)].map; }
  int glossyLevels() const { return settings_.glossy_levels; }
  // Whether updateGlossy has run since init (before it the maps hold nothing).
  bool glossyWritten() const { return glossy_written_; }
  CubeStorage storage() const { return storage_; }
  // E.g. "half float" or "8-bit sRGB (half float unavailable: ...)".
  const std::string& storageDescription() const { return storage_description_; }
  const EnvironmentMapSettings& settings() const { return settings_; }

 private:
  bool allocate(GpuCubeMap& map, int face_size, std::string& error) const;
  // One pass of updateDiffuse over the six faces of `output`.
  bool cosinePass(const gles::Program& program, const GpuCubeMap& input, GpuCubeMap& output, float output_scale,
                  const char* what, std::string& error);
  // One pass of updateDiffuse into a latitude-longitude map; the input is
  // bound by the caller.
  bool latLongPass(const gles::Program& program, GpuLatLongMap& output, float input_scale, float output_scale,
                   const char* what, std::string& error);
  // Checks new_weight and returns the one to use (1 before any diffuse map exists).
  std::optional<float> diffuseBlendWeight(float new_weight, const char* caller, std::string& error) const;
  // Binds the current diffuse map as u_previous (texture unit 1) for
  // diffuse_blend.glsl; the pass then writes diffuse_spare_.
  void bindPreviousDiffuse(const gles::Program& program, float new_weight) const;
  // Makes the freshly written spare the diffuse map.
  void swapDiffuse(float linear_scale);
  // The previous diffuse map's 8-bit scale in the next update's units.
  float previousScaleInNewUnits() const;
  std::optional<ibl::CubeMapRGB> readCube(const GpuCubeMap& map, std::string& error, std::vector<float>* validity) const;

  EnvironmentMapSettings settings_;
  CubeStorage storage_ = CubeStorage::kSrgb8;
  // The maps' texels as allocated and uploaded: RGBA bytes, or the half
  // floats of Capabilities::halfFloatRenderFormat.
  gles::HalfFloatFormat texel_format_{GL_RGBA, GL_UNSIGNED_BYTE};
  std::string storage_description_;
  gles::Program probe_program_;
  gles::Program prefilter_program_;
  gles::Program east_program_;
  gles::Program north_program_;
  gles::Program resample_program_;
  gles::Program sh9_program_;
  gles::FullScreenQuad quad_;
  gles::Framebuffer framebuffer_;
  GpuCubeMap reflection_;
  GpuCubeMap prefiltered_;
  GpuLatLongMap east_latlong_;
  GpuLatLongMap north_latlong_;
  GpuCubeMap diffuse_;
  GpuCubeMap diffuse_spare_;  // the ping-pong partner: the next update writes here, reading diffuse_
  glm::vec3 previous_units_{1.0f};  // setPreviousDiffuseUnits
  bool diffuse_written_ = false;
  struct GlossyLevel {
    gles::Program prefilter_program;  // cosine_irradiance.frag's PREFILTER_PASS with this level's factor
    GpuCubeMap prefiltered;
    GpuCubeMap intermediate;
    GpuCubeMap map;
  };
  std::array<GlossyLevel, 2> glossy_;
  gles::Program glossy_east_program_;
  gles::Program glossy_north_program_;
  bool glossy_written_ = false;
};

// probe_to_cube's uniforms for a view of the ball (the CPU's share of stage
// 2, in double; GL takes them as floats). The vertex shader's face axes are
// R_cam_from_world times kFaceBases' (cube_face_basis.hpp).
struct ProbeToCubeUniforms {
  glm::dmat3 R_cam_from_world{1.0};
  glm::dvec3 eye_ball{0.0};       // (camera centre - ball centre) / radius, camera frame
  glm::dvec3 eye_direction{0.0};  // normalize(eye_ball)
  glm::dvec2 center_normalized{0.0};
  double radius_over_depth = 0.0;
  glm::dvec4 distortion{0.0};  // k1 k2 p1 p2
  double distortion_k3 = 0.0;
  double center_r2 = 0.0;      // |center_normalized|^2
  double center_radial = 1.0;  // 1 + k1 r2 + k2 r2^2 + k3 r2^3 there
  glm::dvec2 focal_over_size{0.0};
  // The centre's texcoord, as a value 11 significant bits hold exactly
  // (16-bit mediump's) plus the rest.
  glm::dvec2 center_texcoord{0.0};
  glm::dvec2 center_texcoord_residual{0.0};
  double inverse_reflectance = 1.0;
  float storage_scale = 1.0f;  // linear_scale of an 8-bit reflection map
};
ProbeToCubeUniforms probeToCubeUniforms(const ibl::MirrorBallView& view, double probe_reflectance);

// GLSL #define lines selecting a storage's encoding in cube_storage.glsl.
std::string cubeStorageDefines(CubeStorage storage);

}  // namespace probelight::passes
