#include "passes/environment_maps.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>

#include <glm/gtc/type_ptr.hpp>

#include "ibl/camera_projection.hpp"
#include "ibl/color_transfer.hpp"
#include "passes/cube_face_basis.hpp"
#include "passes/framebuffer_state_guard.hpp"

namespace probelight::passes {

namespace {

// Pixel positions follow OpenCV's convention (pixel (u, v)'s centre at integer
// (u, v), as projectToPixel and calibration use), while GL puts texel centres
// at (i + 0.5) / size; hence texcoord = (pixel + 0.5) / size, as
// ibl::probeImageToCubeMap assumes.
constexpr double kPixelCenterToTexelCenter = 0.5;

// A 16-bit float's significand: 10 stored bits and the implicit one.
constexpr int kMediumpSignificantBits = 11;

// x rounded to `bits` significant binary digits (to nearest).
double roundToSignificantBits(double x, int bits) {
  if (x == 0.0 || !std::isfinite(x)) return x;
  const int exponent = std::ilogb(x);
  return std::ldexp(std::nearbyint(std::ldexp(x, bits - 1 - exponent)), exponent - (bits - 1));
}

void setFaceUniforms(const gles::Program& program, int face) {
  const FaceBasis& basis = kFaceBases[static_cast<size_t>(face)];
  glUniform3fv(program.uniform("u_face_center"), 1, glm::value_ptr(basis.center));
  glUniform3fv(program.uniform("u_face_s_axis"), 1, glm::value_ptr(basis.s_axis));
  glUniform3fv(program.uniform("u_face_t_axis"), 1, glm::value_ptr(basis.t_axis));
}

}  // namespace

ibl::CosineIrradianceSettings cosineIrradianceSettings(const EnvironmentMapSettings& settings) {
  ibl::CosineIrradianceSettings cosine;
  cosine.prefilter_face_size = settings.prefilter_face_size;
  cosine.intermediate_rows = settings.intermediate_rows;
  cosine.output_face_size = settings.diffuse_face_size;
  cosine.half_taps = settings.blur_half_taps;
  return cosine;
}

ibl::GlossyLevelSettings glossyLevelSettings(const EnvironmentMapSettings& settings, int level) {
  const auto i = static_cast<size_t>(level);
  ibl::GlossyLevelSettings glossy;
  glossy.exponent = settings.glossy_exponent[i];
  glossy.prefilter_face_size = settings.glossy_face_size[i];
  glossy.intermediate_face_size = settings.glossy_intermediate_face_size[i];
  glossy.output_face_size = settings.glossy_face_size[i];
  glossy.half_taps = settings.glossy_half_taps;
  glossy.pole_direct_deg = settings.glossy_pole_direct_deg;
  return glossy;
}

std::string cubeStorageDefines(CubeStorage storage) {
  return storage == CubeStorage::kSrgb8 ? "#define CUBE_STORAGE_SRGB8 1\n" : "";
}

bool EnvironmentMaps::init(const gles::Capabilities& capabilities, const EnvironmentMapSettings& settings,
                           std::string& error) {
  settings_ = settings;
  for (int size : {settings.reflection_face_size, settings.prefilter_face_size, settings.diffuse_face_size}) {
    if (size < 2 || size > capabilities.max_cube_map_size_px) {
      error = "EnvironmentMaps: cube face size " + std::to_string(size) + " must be in [2, " +
              std::to_string(capabilities.max_cube_map_size_px) + "] (the GPU's GL_MAX_CUBE_MAP_TEXTURE_SIZE)";
      return false;
    }
  }
  // The prefilter averages whole blocks, as ibl::downsampleCubeMap; its
  // loop bound is a compile-time constant (GLSL ES 1.00).
  const int prefilter_factor = settings.reflection_face_size / settings.prefilter_face_size;
  if (settings.reflection_face_size % settings.prefilter_face_size != 0 || prefilter_factor > 8) {
    error = "EnvironmentMaps: prefilter_face_size " + std::to_string(settings.prefilter_face_size) +
            " must divide reflection_face_size " + std::to_string(settings.reflection_face_size) +
            " by a factor of 1..8";
    return false;
  }
  if (settings.normal_iterations < 0 || settings.normal_iterations > 16 || settings.blur_half_taps < 0 ||
      settings.blur_half_taps > 32) {
    error = "EnvironmentMaps: normal_iterations must be 0..16 and blur_half_taps 0..32";
    return false;
  }
  // Even: the north pass's taps are whole rows, symmetric about the texel.
  if (settings.intermediate_rows < 4 || settings.intermediate_rows > 128 || settings.intermediate_rows % 2 != 0 ||
      2 * settings.intermediate_rows > capabilities.max_texture_size_px) {
    error = "EnvironmentMaps: intermediate_rows " + std::to_string(settings.intermediate_rows) +
            " must be even, in [4, 128], and twice it no more than the GPU's GL_MAX_TEXTURE_SIZE " +
            std::to_string(capabilities.max_texture_size_px);
    return false;
  }
  if (settings.glossy_levels < 0 || settings.glossy_levels > 2 || settings.glossy_half_taps < 1 ||
      settings.glossy_half_taps > 32 || !(settings.glossy_pole_direct_deg >= 0.0 && settings.glossy_pole_direct_deg <= 90.0)) {
    error = "EnvironmentMaps: glossy_levels must be 0..2, glossy_half_taps 1..32 and glossy_pole_direct_deg 0..90";
    return false;
  }
  for (int level = 0; level < settings.glossy_levels; ++level) {
    const auto i = static_cast<size_t>(level);
    const int size = settings.glossy_face_size[i];
    const int intermediate = settings.glossy_intermediate_face_size[i];
    if (size < 2 || intermediate < 2 || intermediate > capabilities.max_cube_map_size_px ||
        settings.reflection_face_size % size != 0 || settings.reflection_face_size / size > 8 ||
        !(settings.glossy_exponent[i] >= 1.0)) {
      error = "EnvironmentMaps: glossy level " + std::to_string(level) + ": glossy_face_size " + std::to_string(size) +
              " must divide reflection_face_size by a factor of 1..8, glossy_intermediate_face_size must be in [2, " +
              std::to_string(capabilities.max_cube_map_size_px) + "] and glossy_exponent >= 1";
      return false;
    }
  }
  framebuffer_ = gles::Framebuffer::create();
  if (!quad_.init(error)) return false;

  storage_ = CubeStorage::kSrgb8;
  texel_format_ = {GL_RGBA, GL_UNSIGNED_BYTE};
  if (const std::optional<gles::HalfFloatFormat> half = capabilities.halfFloatRenderFormat()) {
    // The extensions promise it, but only a complete framebuffer proves it.
    std::string why;
    auto probe = gles::createCubeTexture(4, half->internal_format, GL_RGBA, half->type, why);
    GLenum status = GL_NONE;
    if (probe) {
      FramebufferStateGuard guard;
      glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, probe->id(), 0);
      status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, 0);
      why = gles::framebufferStatusName(status);
    }
    if (status == GL_FRAMEBUFFER_COMPLETE) {
      storage_ = CubeStorage::kLinearHalfFloat;
      texel_format_ = *half;
      storage_description_ = "half float (" + capabilities.halfFloatRoute() + ")";
    } else {
      storage_description_ =
          "8-bit sRGB (half float render target unusable: " + why + "; " + capabilities.halfFloatRoute() + ")";
    }
  } else {
    storage_description_ = "8-bit sRGB (" + capabilities.halfFloatRoute() + ")";
  }

  const std::string storage_defines = cubeStorageDefines(storage_);
  std::string transfer_define;
  if (settings.camera_transfer.curve == ibl::CameraTransfer::Curve::kGamma) {
    if (!(settings.camera_transfer.gamma > 0.0 && settings.camera_transfer.gamma <= 5.0)) {
      error = "camera transfer gamma must be in (0, 5]";
      return false;
    }
    transfer_define = "#define CAMERA_TRANSFER_GAMMA\n";
  } else if (settings.camera_transfer.curve == ibl::CameraTransfer::Curve::kLinear) {
    transfer_define = "#define CAMERA_TRANSFER_LINEAR\n";
  }
  auto probe_program = gles::Program::fromEmbedded(
      "probe_to_cube.vert", "probe_to_cube.frag",
      storage_defines + transfer_define + "#define NORMAL_ITERATIONS " + std::to_string(settings.normal_iterations) +
          "\n",
      error);
  if (!probe_program) return false;
  probe_program_ = std::move(*probe_program);
  const std::string cosine_defines = storage_defines + "#define HALF_TAPS " +
                                     std::to_string(settings.blur_half_taps) + "\n#define PREFILTER_FACTOR " +
                                     std::to_string(prefilter_factor) + "\n#define LATLONG_ROWS " +
                                     std::to_string(settings.intermediate_rows) + "\n";
  for (auto [program, pass] : {std::pair{&prefilter_program_, "PREFILTER_PASS"}, std::pair{&east_program_, "EAST_PASS"},
                               std::pair{&north_program_, "NORTH_PASS"}, std::pair{&resample_program_, "RESAMPLE_PASS"}}) {
    auto compiled = gles::Program::fromEmbedded("cube_face.vert", "cosine_irradiance.frag",
                                                cosine_defines + "#define " + pass + " 1\n", error);
    if (!compiled) return false;
    *program = std::move(*compiled);
  }
  auto sh9_program = gles::Program::fromEmbedded("cube_face.vert", "sh9_irradiance.frag", storage_defines, error);
  if (!sh9_program) return false;
  sh9_program_ = std::move(*sh9_program);

  if (!allocate(reflection_, settings.reflection_face_size, error)) return false;
  if (!allocate(prefiltered_, settings.prefilter_face_size, error)) return false;
  for (GpuLatLongMap* map : {&east_latlong_, &north_latlong_}) {
    auto texture = gles::createTexture2D(2 * settings.intermediate_rows, settings.intermediate_rows,
                                         texel_format_.internal_format, GL_RGBA, texel_format_.type, GL_NEAREST,
                                         nullptr, error);
    if (!texture) return false;
    map->texture = std::move(*texture);
    map->rows = settings.intermediate_rows;
  }
  if (!allocate(diffuse_, settings.diffuse_face_size, error)) return false;
  if (!allocate(diffuse_spare_, settings.diffuse_face_size, error)) return false;
  diffuse_written_ = false;

  if (settings.glossy_levels > 0) {
    const std::string glossy_defines = storage_defines + "#define HALF_TAPS " + std::to_string(settings.glossy_half_taps) + "\n";
    for (auto [program, pass] : {std::pair{&glossy_east_program_, "EAST_PASS"}, std::pair{&glossy_north_program_, "NORTH_PASS"}}) {
      auto compiled = gles::Program::fromEmbedded("cube_face.vert", "glossy_lobe.frag",
                                                  glossy_defines + "#define " + pass + " 1\n", error);
      if (!compiled) return false;
      *program = std::move(*compiled);
    }
  }
  for (int level = 0; level < settings.glossy_levels; ++level) {
    GlossyLevel& glossy = glossy_[static_cast<size_t>(level)];
    const int size = settings.glossy_face_size[static_cast<size_t>(level)];
    auto prefilter = gles::Program::fromEmbedded(
        "cube_face.vert", "cosine_irradiance.frag",
        storage_defines + "#define PREFILTER_FACTOR " + std::to_string(settings.reflection_face_size / size) +
            "\n#define PREFILTER_PASS 1\n",
        error);
    if (!prefilter) return false;
    glossy.prefilter_program = std::move(*prefilter);
    if (!allocate(glossy.prefiltered, size, error)) return false;
    if (!allocate(glossy.intermediate, settings.glossy_intermediate_face_size[static_cast<size_t>(level)], error))
      return false;
    if (!allocate(glossy.map, size, error)) return false;
  }
  glossy_written_ = false;
  return gles::checkGl("EnvironmentMaps::init", error);
}

bool EnvironmentMaps::allocate(GpuCubeMap& map, int face_size, std::string& error) const {
  auto texture = gles::createCubeTexture(face_size, texel_format_.internal_format, GL_RGBA, texel_format_.type, error);
  if (!texture) return false;
  map.texture = std::move(*texture);
  map.face_size = face_size;
  map.linear_scale = 1.0f;
  return true;
}

ProbeToCubeUniforms probeToCubeUniforms(const ibl::MirrorBallView& view, double probe_reflectance) {
  ProbeToCubeUniforms u;
  const CameraIntrinsics& camera = view.camera;
  const glm::dvec3 center_cam = view.pose.toCamera(view.center_w);
  u.R_cam_from_world = view.pose.R_cam_from_world;
  // The shader works in the camera's frame: the eye relative to the ball
  // centre, in radii, is -centre_cam / radius there.
  u.eye_ball = -center_cam / view.radius_m;
  u.eye_direction = glm::normalize(u.eye_ball);
  u.center_normalized = {center_cam.x / center_cam.z, center_cam.y / center_cam.z};
  u.radius_over_depth = view.radius_m / center_cam.z;
  u.distortion = {camera.distortion[0], camera.distortion[1], camera.distortion[2], camera.distortion[3]};
  u.distortion_k3 = camera.distortion[4];
  u.center_r2 = glm::dot(u.center_normalized, u.center_normalized);
  u.center_radial = 1.0 + u.center_r2 * (u.distortion[0] + u.center_r2 * (u.distortion[1] + u.center_r2 * u.distortion_k3));
  const glm::dvec2 center_px = ibl::projectToPixel(camera, center_cam);
  const glm::dvec2 size_px{camera.width_px, camera.height_px};
  const glm::dvec2 center_texcoord = (center_px + kPixelCenterToTexelCenter) / size_px;
  u.center_texcoord = {roundToSignificantBits(center_texcoord.x, kMediumpSignificantBits),
                       roundToSignificantBits(center_texcoord.y, kMediumpSignificantBits)};
  u.center_texcoord_residual = center_texcoord - u.center_texcoord;
  u.focal_over_size = glm::dvec2(camera.fx_px, camera.fy_px) / size_px;
  u.inverse_reflectance = 1.0 / probe_reflectance;
  u.storage_scale = static_cast<float>(std::max(1.0, 1.0 / probe_reflectance));
  return u;
}

bool EnvironmentMaps::updateReflection(const CameraFrameTexture& camera_frame, const ibl::MirrorBallView& view,
                                       double probe_reflectance, std::string& error) {
  if (camera_frame.empty()) {
    error = "EnvironmentMaps::updateReflection: no camera frame uploaded yet";
    return false;
  }
  if (camera_frame.widthPx() != view.camera.width_px || camera_frame.heightPx() != view.camera.height_px) {
    error = "EnvironmentMaps::updateReflection: camera frame is " + std::to_string(camera_frame.widthPx()) + "x" +
            std::to_string(camera_frame.heightPx()) + " but the calibration is for " +
            std::to_string(view.camera.width_px) + "x" + std::to_string(view.camera.height_px) +
            "; recalibrate or select the calibrated camera mode";
    return false;
  }
  if (!(probe_reflectance > 0.0) || !(view.radius_m > 0.0)) {
    error = "EnvironmentMaps::updateReflection: probe reflectance and radius must be positive (check rig.yaml)";
    return false;
  }
  const glm::dvec3 center_cam = view.pose.toCamera(view.center_w);
  if (center_cam.z <= view.radius_m) {
    error = "EnvironmentMaps::updateReflection: the mirror ball is behind or around the camera (depth " +
            std::to_string(center_cam.z) + " m); check the pose and rig.yaml's probe_center_w";
    return false;
  }
  const ProbeToCubeUniforms u = probeToCubeUniforms(view, probe_reflectance);

  FramebufferStateGuard guard;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, reflection_.face_size, reflection_.face_size);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  probe_program_.use();
  auto set3 = [&](const char* name, const glm::dvec3& v) {
    glUniform3f(probe_program_.uniform(name), static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
  };
  auto set2 = [&](const char* name, const glm::dvec2& v) {
    glUniform2f(probe_program_.uniform(name), static_cast<float>(v.x), static_cast<float>(v.y));
  };
  set3("u_eye_ball", u.eye_ball);
  set3("u_eye_direction", u.eye_direction);
  set2("u_center_normalized", u.center_normalized);
  glUniform1f(probe_program_.uniform("u_radius_over_depth"), static_cast<float>(u.radius_over_depth));
  glUniform4f(probe_program_.uniform("u_distortion"), static_cast<float>(u.distortion[0]),
              static_cast<float>(u.distortion[1]), static_cast<float>(u.distortion[2]),
              static_cast<float>(u.distortion[3]));
  glUniform1f(probe_program_.uniform("u_distortion_k3"), static_cast<float>(u.distortion_k3));
  glUniform1f(probe_program_.uniform("u_center_r2"), static_cast<float>(u.center_r2));
  glUniform1f(probe_program_.uniform("u_center_radial"), static_cast<float>(u.center_radial));
  set2("u_focal_over_size", u.focal_over_size);
  set2("u_center_texcoord", u.center_texcoord);
  set2("u_center_texcoord_residual", u.center_texcoord_residual);
  glUniform1f(probe_program_.uniform("u_inverse_reflectance"), static_cast<float>(u.inverse_reflectance));
  glUniform1f(probe_program_.uniform("u_camera_gamma"), static_cast<float>(settings_.camera_transfer.gamma));
  glUniform1f(probe_program_.uniform("u_storage_scale"), u.storage_scale);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, camera_frame.texture());
  glUniform1i(probe_program_.uniform("u_camera"), 0);
  const GLint position = probe_program_.attribute("a_position");
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X + static_cast<GLenum>(face),
                           reflection_.texture.id(), 0);
    const FaceBasis& basis = kFaceBases[static_cast<size_t>(face)];
    const glm::dmat3& rotation = u.R_cam_from_world;
    set3("u_face_center_cam", rotation * glm::dvec3(basis.center));
    set3("u_face_s_axis_cam", rotation * glm::dvec3(basis.s_axis));
    set3("u_face_t_axis_cam", rotation * glm::dvec3(basis.t_axis));
    quad_.draw(position);
  }
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, 0);
  reflection_.linear_scale = storage_ == CubeStorage::kSrgb8 ? u.storage_scale : 1.0f;
  return gles::checkGl("EnvironmentMaps::updateReflection", error);
}


bool EnvironmentMaps::cosinePass(const gles::Program& program, const GpuCubeMap& input, GpuCubeMap& output,
                                 float output_scale, const char* what, std::string& error) {
  FramebufferStateGuard guard;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, output.face_size, output.face_size);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  program.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_CUBE_MAP, input.texture.id());
  glUniform1i(program.uniform("u_input"), 0);
  glUniform1f(program.uniform("u_input_face_size"), static_cast<float>(input.face_size));
  glUniform1f(program.uniform("u_input_scale"), input.linear_scale);
  glUniform1f(program.uniform("u_output_scale"), output_scale);
  glUniform1f(program.uniform("u_output_face_size"), static_cast<float>(output.face_size));  // prefilter only
  const GLint position = program.attribute("a_position");
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X + static_cast<GLenum>(face),
                           output.texture.id(), 0);
    setFaceUniforms(program, face);
    glUniform1f(program.uniform("u_face_index"), static_cast<float>(face));  // prefilter only
    quad_.draw(position);
  }
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, 0);
  output.linear_scale = output_scale;
  return gles::checkGl(what, error);
}

std::optional<float> EnvironmentMaps::diffuseBlendWeight(float new_weight, const char* caller,
                                                         std::string& error) const {
  if (!(new_weight >= 0.0f && new_weight <= 1.0f)) {
    error = std::string(caller) + ": new_weight " + std::to_string(new_weight) + " must be in [0, 1]";
    return std::nullopt;
  }
  return diffuse_written_ ? new_weight : 1.0f;
}

void EnvironmentMaps::bindPreviousDiffuse(const gles::Program& program, float new_weight) const {
  // Unit 1 always holds a cube map, so the sampler is valid even when the
  // weight-1 branch never reads it.
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_CUBE_MAP, diffuse_.texture.id());
  glUniform1i(program.uniform("u_previous"), 1);
  glUniform1f(program.uniform("u_previous_scale"), diffuse_.linear_scale);
  glUniform3fv(program.uniform("u_previous_units"), 1, glm::value_ptr(previous_units_));
  glUniform1f(program.uniform("u_new_weight"), new_weight);
  glActiveTexture(GL_TEXTURE0);
}

float EnvironmentMaps::previousScaleInNewUnits() const {
  return diffuse_.linear_scale * std::max({previous_units_.r, previous_units_.g, previous_units_.b});
}

void EnvironmentMaps::swapDiffuse(float linear_scale) {
  std::swap(diffuse_, diffuse_spare_);
  diffuse_.linear_scale = linear_scale;
  diffuse_written_ = true;
}

namespace {
// 8-bit output scale when blending: max(w a + (1 - w) b) <= w max(a) +
// (1 - w) max(b), so w * new scale + (1 - w) * previous scale always holds
// the result, and it decays back to the new scale instead of ratcheting up.
float blendedScale(float new_scale, float previous_scale, float new_weight) {
  return new_weight >= 1.0f ? new_scale : new_weight * new_scale + (1.0f - new_weight) * previous_scale;
}
}  // namespace

bool EnvironmentMaps::latLongPass(const gles::Program& program, GpuLatLongMap& output, float input_scale,
                                  float output_scale, const char* what, std::string& error) {
  FramebufferStateGuard guard;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, 2 * output.rows, output.rows);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  program.use();
  glUniform1f(program.uniform("u_input_scale"), input_scale);
  glUniform1f(program.uniform("u_output_scale"), output_scale);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, output.texture.id(), 0);
  quad_.draw(program.attribute("a_position"));
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, 0, 0);
  output.linear_scale = output_scale;
  return gles::checkGl(what, error);
}

bool EnvironmentMaps::updateDiffuse(std::string& error, float new_weight) {
  const auto weight = diffuseBlendWeight(new_weight, "EnvironmentMaps::updateDiffuse", error);
  if (!weight) return false;
  // Every map below is a weighted mean of the reflection map's values (the
  // premultiplied ones times validity <= 1, and the division by coverage
  // gives back a weighted mean of radiance), so the reflection map's scale
  // holds all of them.
  const float input_scale = reflection_.linear_scale;
  if (!cosinePass(prefilter_program_, reflection_, prefiltered_, input_scale, "EnvironmentMaps prefilter pass", error))
    return false;
  east_program_.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_CUBE_MAP, prefiltered_.texture.id());
  glUniform1i(east_program_.uniform("u_input"), 0);
  glUniform1f(east_program_.uniform("u_input_face_size"), static_cast<float>(prefiltered_.face_size));
  if (!latLongPass(east_program_, east_latlong_, prefiltered_.linear_scale, input_scale, "EnvironmentMaps east pass",
                   error))
    return false;
  // The latitude-longitude maps are 2D textures: on units of their own, so
  // that no unit is asked for a cube and a 2D sampler at once (GLES2 refuses
  // a draw where two active samplers of different types share a unit).
  north_program_.use();
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, east_latlong_.texture.id());
  glUniform1i(north_program_.uniform("u_latlong"), 1);
  glActiveTexture(GL_TEXTURE0);
  if (!latLongPass(north_program_, north_latlong_, east_latlong_.linear_scale, input_scale,
                   "EnvironmentMaps north pass", error))
    return false;
  const float scale =
      storage_ == CubeStorage::kSrgb8 ? blendedScale(input_scale, previousScaleInNewUnits(), *weight) : 1.0f;
  resample_program_.use();
  bindPreviousDiffuse(resample_program_, *weight);
  // Unit 2 (unit 1 holds the previous diffuse cube for the blend).
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, north_latlong_.texture.id());
  glUniform1i(resample_program_.uniform("u_latlong"), 2);
  glActiveTexture(GL_TEXTURE0);
  if (!cosinePass(resample_program_, prefiltered_, diffuse_spare_, scale, "EnvironmentMaps resampling pass", error))
    return false;
  // cosinePass set u_input_scale to the prefiltered map's scale; the north
  // map has the same one (both are the reflection map's).
  swapDiffuse(scale);
  return true;
}

bool EnvironmentMaps::updateGlossy(std::string& error) {
  // Weighted means of the reflection map's values, as in updateDiffuse: its
  // scale holds every map below.
  const float scale = reflection_.linear_scale;
  for (int level = 0; level < settings_.glossy_levels; ++level) {
    GlossyLevel& glossy = glossy_[static_cast<size_t>(level)];
    const ibl::GlossyLevelSettings lobe = glossyLevelSettings(settings_, level);
    if (!cosinePass(glossy.prefilter_program, reflection_, glossy.prefiltered, scale, "EnvironmentMaps glossy prefilter",
                    error))
      return false;
    const float step = static_cast<float>(ibl::glossyTapAngleRad(lobe.exponent, lobe.half_taps, 1));
    for (const gles::Program* program : {&glossy_east_program_, &glossy_north_program_}) {
      program->use();
      glUniform1f(program->uniform("u_tap_step_rad"), step);
      glUniform1f(program->uniform("u_east_power"), static_cast<float>(lobe.exponent + 1.0));
      glUniform1f(program->uniform("u_north_power"), static_cast<float>(lobe.exponent));
    }
    if (!cosinePass(glossy_east_program_, glossy.prefiltered, glossy.intermediate, scale, "EnvironmentMaps glossy east",
                    error))
      return false;
    glossy_north_program_.use();
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_CUBE_MAP, glossy.prefiltered.texture.id());
    glUniform1i(glossy_north_program_.uniform("u_prefiltered"), 2);
    glUniform1f(glossy_north_program_.uniform("u_prefiltered_face_size"), static_cast<float>(glossy.prefiltered.face_size));
    glUniform1f(glossy_north_program_.uniform("u_prefiltered_scale"), glossy.prefiltered.linear_scale);
    glUniform1f(glossy_north_program_.uniform("u_pole_cosine"),
                static_cast<float>(std::cos(lobe.pole_direct_deg * M_PI / 180.0)));
    glActiveTexture(GL_TEXTURE0);
    if (!cosinePass(glossy_north_program_, glossy.intermediate, glossy.map, scale, "EnvironmentMaps glossy north",
                    error))
      return false;
  }
  glossy_written_ = settings_.glossy_levels > 0;
  return true;
}

GLuint EnvironmentMaps::glossyCube(int level) const {
  return level >= 0 && level < settings_.glossy_levels ? glossy_[static_cast<size_t>(level)].map.texture.id() : 0;
}

bool EnvironmentMaps::updateDiffuseFromSH9(const ibl::SH9RGB& sh, std::string& error, float new_weight) {
  const auto weight = diffuseBlendWeight(new_weight, "EnvironmentMaps::updateDiffuseFromSH9", error);
  if (!weight) return false;
  const std::array<glm::dvec3, ibl::kSH9Count> polynomial = ibl::sh9DiffusePolynomial(sh);
  std::array<float, 3 * ibl::kSH9Count> uniforms{};
  for (int k = 0; k < ibl::kSH9Count; ++k) {
    for (int c = 0; c < 3; ++c) uniforms[static_cast<size_t>(3 * k + c)] = static_cast<float>(polynomial[k][c]);
    if (!std::isfinite(polynomial[k].x + polynomial[k].y + polynomial[k].z)) {
      error = "EnvironmentMaps::updateDiffuseFromSH9: coefficient " + std::to_string(k) + " is not finite";
      return false;
    }
  }
  float scale = 1.0f;
  if (storage_ == CubeStorage::kSrgb8) {
    // The largest value the map will hold, at its own texel centres (where
    // the shader evaluates it): nothing clips, and dark maps keep scale 1.
    double largest = 1.0;
    const int n = diffuse_spare_.face_size;
    for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          const glm::dvec3 d = ibl::cubeTexelCenterDirection(face, x, y, n);
          const double monomials[ibl::kSH9Count] = {1.0,       d.x,       d.y,       d.z,        d.x * d.y,
                                                     d.y * d.z, d.x * d.z, d.z * d.z, d.x * d.x - d.y * d.y};
          glm::dvec3 value(0.0);
          for (int k = 0; k < ibl::kSH9Count; ++k) value += polynomial[k] * monomials[k];
          largest = std::max({largest, value.x, value.y, value.z});
        }
      }
    }
    scale = blendedScale(static_cast<float>(largest), previousScaleInNewUnits(), *weight);
  }

  FramebufferStateGuard guard;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, diffuse_spare_.face_size, diffuse_spare_.face_size);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  sh9_program_.use();
  bindPreviousDiffuse(sh9_program_, *weight);
  glUniform3fv(sh9_program_.uniform("u_sh[0]"), ibl::kSH9Count, uniforms.data());
  glUniform1f(sh9_program_.uniform("u_output_scale"), scale);
  const GLint position = sh9_program_.attribute("a_position");
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X + static_cast<GLenum>(face),
                           diffuse_spare_.texture.id(), 0);
    setFaceUniforms(sh9_program_, face);
    quad_.draw(position);
  }
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X, 0, 0);
  if (!gles::checkGl("EnvironmentMaps::updateDiffuseFromSH9", error)) return false;
  swapDiffuse(scale);
  return true;
}

}  // namespace probelight::passes
