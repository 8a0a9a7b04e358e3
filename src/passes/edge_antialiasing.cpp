#include "passes/edge_antialiasing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ibl/camera_projection.hpp"

namespace probelight::passes {

const char* edgeStrategyName(EdgeStrategy strategy) {
  switch (strategy) {
    case EdgeStrategy::kMultisampleConfig: return "multisample_config";
    case EdgeStrategy::kMultisampleRenderToTexture: return "multisample_render_to_texture";
    case EdgeStrategy::kOrderedGridSupersampling: return "ordered_grid_supersampling";
    default: return "off";
  }
}

EdgeAntialiasing chooseEdgeAntialiasing(const gles::Capabilities& capabilities, int requested_samples,
                                        int target_samples, int width_px, int height_px) {
  EdgeAntialiasing choice;
  choice.requested_samples = requested_samples;
  if (requested_samples <= 1) {
    choice.reason = "edge_samples " + std::to_string(requested_samples) + ": off";
    return choice;
  }
  if (target_samples >= 2) {
    choice.strategy = EdgeStrategy::kMultisampleConfig;
    choice.samples = target_samples;
    choice.reason = "the framebuffer drawn into has " + std::to_string(target_samples) + " samples";
    return choice;
  }
  if (capabilities.multisampled_render_to_texture && capabilities.max_samples >= 2) {
    choice.strategy = EdgeStrategy::kMultisampleRenderToTexture;
    choice.samples = std::min(requested_samples, capabilities.max_samples);
    choice.reason = "GL_EXT_multisampled_render_to_texture, up to " + std::to_string(capabilities.max_samples) +
                    " samples";
    return choice;
  }
  // The smallest even grid with at least the samples asked for, at most 4 x 4.
  int grid = requested_samples <= 4 ? 2 : kMaxSupersamplingGrid;
  // Every limit the layer meets: its texture, its depth renderbuffer, the
  // viewport it is drawn with. 0 (not probed) counts as no limit known.
  int limit = 1 << 30;
  for (int bound : {capabilities.max_texture_size_px, capabilities.max_renderbuffer_size_px, capabilities.max_viewport_px})
    if (bound > 0) limit = std::min(limit, bound);
  while (grid >= 2 && (static_cast<long long>(grid) * width_px > limit || static_cast<long long>(grid) * height_px > limit))
    grid /= 2;
  if (grid < 2) {
    choice.reason = "no multisampling, and a " + std::to_string(2 * width_px) + "x" + std::to_string(2 * height_px) +
                    " supersampled layer exceeds the GPU's " + std::to_string(limit) + " px limit: off";
    return choice;
  }
  choice.strategy = EdgeStrategy::kOrderedGridSupersampling;
  choice.grid = grid;
  choice.samples = grid * grid;
  choice.reason = "no multisampling offered (no GL_EXT_multisampled_render_to_texture, single-sampled target): " +
                  std::to_string(grid) + "x" + std::to_string(grid) + " supersampled layer";
  return choice;
}

PixelRect projectedBounds(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const glm::dvec3& min_w,
                          const glm::dvec3& max_w, double near_m, int margin_px) {
  const PixelRect whole{0, 0, camera.width_px, camera.height_px};
  // The pinhole image of the box: inside the rectangle of its corners'.
  glm::dvec2 low(std::numeric_limits<double>::infinity()), high(-std::numeric_limits<double>::infinity());
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 w((corner & 1) ? max_w.x : min_w.x, (corner & 2) ? max_w.y : min_w.y,
                       (corner & 4) ? max_w.z : min_w.z);
    const glm::dvec3 c = pose.R_cam_from_world * w + pose.t_cam_from_world;
    if (!(c.z >= near_m) || !std::isfinite(c.x) || !std::isfinite(c.y)) return whole;
    low = glm::min(low, glm::dvec2(c) / c.z);
    high = glm::max(high, glm::dvec2(c) / c.z);
  }
  // How far out the image reaches, undistorted: beyond 1.5 times that the
  // polynomial is past its calibrated range and may fold back.
  double image_radius2 = 0.0;
  for (const glm::dvec2 pixel : {glm::dvec2(-0.5, -0.5), glm::dvec2(camera.width_px - 0.5, -0.5),
                                 glm::dvec2(-0.5, camera.height_px - 0.5),
                                 glm::dvec2(camera.width_px - 0.5, camera.height_px - 0.5)}) {
    const glm::dvec3 ray = ibl::pixelToCameraRay(camera, pixel);
    image_radius2 = std::max(image_radius2, ray.x * ray.x + ray.y * ray.y);
  }
  const double far2 = std::max(low.x * low.x, high.x * high.x) + std::max(low.y * low.y, high.y * high.y);
  if (!(far2 <= 2.25 * image_radius2)) return whole;
  // The distorted outline of that rectangle.
  constexpr int kSamplesPerSide = 32;
  glm::dvec2 pixel_low(std::numeric_limits<double>::infinity()), pixel_high(-std::numeric_limits<double>::infinity());
  for (int side = 0; side < 4; ++side)
    for (int i = 0; i <= kSamplesPerSide; ++i) {
      const double t = static_cast<double>(i) / kSamplesPerSide;
      const glm::dvec2 n = side == 0   ? glm::dvec2(glm::mix(low.x, high.x, t), low.y)
                           : side == 1 ? glm::dvec2(glm::mix(low.x, high.x, t), high.y)
                           : side == 2 ? glm::dvec2(low.x, glm::mix(low.y, high.y, t))
                                       : glm::dvec2(high.x, glm::mix(low.y, high.y, t));
      const glm::dvec2 pixel = ibl::projectToPixel(camera, {n.x, n.y, 1.0});
      if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y)) return whole;
      pixel_low = glm::min(pixel_low, pixel);
      pixel_high = glm::max(pixel_high, pixel);
    }
  // Pixel p's centre is at p (OpenCV's convention, as the shader's
  // NDC = 2 (p + 0.5) / size - 1): a vertex at u touches column floor(u + 0.5).
  const double x0 = std::floor(pixel_low.x + 0.5) - margin_px, x1 = std::ceil(pixel_high.x + 0.5) + margin_px;
  const double y0 = std::floor(pixel_low.y + 0.5) - margin_px, y1 = std::ceil(pixel_high.y + 0.5) + margin_px;
  const int left = static_cast<int>(std::clamp(x0, 0.0, static_cast<double>(camera.width_px)));
  const int right = static_cast<int>(std::clamp(x1, 0.0, static_cast<double>(camera.width_px)));
  const int top = static_cast<int>(std::clamp(y0, 0.0, static_cast<double>(camera.height_px)));
  const int bottom = static_cast<int>(std::clamp(y1, 0.0, static_cast<double>(camera.height_px)));
  if (right <= left || bottom <= top) return PixelRect{};
  return PixelRect{left, top, right - left, bottom - top};
}

bool EdgeLayer::init(const gles::Capabilities& capabilities, const EdgeAntialiasing& choice, int width_px,
                     int height_px, std::string& error) {
  layer_.reset();
  depth_.reset();
  framebuffer_.reset();
  bytes_ = 0;
  samples_ = choice.samples;
  choice_ = choice;
  width_px_ = width_px;
  height_px_ = height_px;
  if (!choice.usesLayer() || width_px <= 0 || height_px <= 0) {
    error = "EdgeLayer: " + std::string(edgeStrategyName(choice.strategy)) + " at " + std::to_string(width_px) + "x" +
            std::to_string(height_px) + " needs no layer";
    return false;
  }
  const bool multisampled = choice.strategy == EdgeStrategy::kMultisampleRenderToTexture;
  if (multisampled && !capabilities.multisampled_render_to_texture) {
    error = "EdgeLayer: GL_EXT_multisampled_render_to_texture is not offered";
    return false;
  }
  const int layer_width = width_px * choice.grid, layer_height = height_px * choice.grid;
  // GRID 1 reads one texel of a layer the GPU already resolved; the grids
  // read 2 x 2 blocks with bilinear fetches at their corners.
  auto texture = gles::createTexture2D(layer_width, layer_height, GL_RGBA, GL_UNSIGNED_BYTE,
                                       choice.grid == 1 ? GL_NEAREST : GL_LINEAR, nullptr, error);
  if (!texture) return false;
  depth_ = gles::Renderbuffer::create();
  glBindRenderbuffer(GL_RENDERBUFFER, depth_.id());
  if (multisampled)
    capabilities.renderbuffer_storage_multisample(GL_RENDERBUFFER, choice.samples, GL_DEPTH_COMPONENT16, layer_width,
                                                  layer_height);
  else
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, layer_width, layer_height);
  glBindRenderbuffer(GL_RENDERBUFFER, 0);
  if (!gles::checkGl("EdgeLayer depth renderbuffer", error)) return false;
  framebuffer_ = gles::Framebuffer::create();
  GLint previous = 0;
  glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  if (multisampled)
    capabilities.framebuffer_texture_2d_multisample(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                                                    texture->id(), 0, choice.samples);
  else
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture->id(), 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.id());
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  GLint samples = 0;
  glGetIntegerv(GL_SAMPLES, &samples);
  glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = "EdgeLayer " + std::to_string(layer_width) + "x" + std::to_string(layer_height) + " (" +
            edgeStrategyName(choice.strategy) + ", " + std::to_string(choice.samples) +
            " samples) is incomplete: " + gles::framebufferStatusName(status);
    framebuffer_.reset();
    depth_.reset();
    return false;
  }
  // The EXT may round the count up to one the GPU has: the count it gave.
  if (multisampled && samples >= 2) samples_ = samples;
  layer_ = std::move(*texture);
  const std::uint64_t texels = static_cast<std::uint64_t>(layer_width) * static_cast<std::uint64_t>(layer_height);
  // RGBA8 colour, 16-bit depth; a multisampled layer holds its samples too
  // (in tile memory on a tiler, but counted as a desktop GPU would).
  const auto per_texel_samples = static_cast<std::uint64_t>(multisampled ? samples_ : 1);
  bytes_ = texels * 4 + texels * 2 * per_texel_samples + (multisampled ? texels * 4 * per_texel_samples : 0);

  const std::string defines = "#define GRID " + std::to_string(choice.grid) + "\n";
  program_ = gles::Program::fromEmbedded("model_edges_composite.vert", "model_edges_composite.frag", defines, error);
  if (!program_) return false;
  noise_program_.reset();
  if (!quad_.init(error)) return false;
  return gles::checkGl("EdgeLayer::init", error);
}

void EdgeLayer::begin(const PixelRect& region) {
  region_ = region;
  saved_.capture();
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  const int k = choice_.grid;
  glViewport(0, 0, width_px_ * k, height_px_ * k);
  // GL's window rows count from the bottom; the region's from the top.
  glEnable(GL_SCISSOR_TEST);
  glScissor(k * region.x, k * (height_px_ - region.y - region.height), k * region.width, k * region.height);
  glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void EdgeLayer::restore() {
  saved_.restore();
}

bool EdgeLayer::composite(std::string& error, const SensorNoiseMatch* noise, const SensorNoiseTexture* texture) {
  const bool add_noise = noise != nullptr && texture != nullptr && texture->valid() && addsNoiseAfterResolve();
  if (add_noise && !noise_program_) {
    noise_program_ = gles::Program::fromEmbedded(
        "model_edges_composite.vert", "model_edges_composite.frag",
        "#define GRID " + std::to_string(choice_.grid) + "\n" + cameraResponseDefines({}, true), error);
    if (!noise_program_) {
      restore();
      return false;
    }
  }
  const gles::Program& program = add_noise ? *noise_program_ : *program_;
  restore();
  // The frame's viewport covers the frame one to one (the renderer's contract).
  glEnable(GL_SCISSOR_TEST);
  glScissor(saved_.viewport[0] + region_.x, saved_.viewport[1] + (height_px_ - region_.y - region_.height),
            region_.width, region_.height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  program.use();
  if (add_noise) setCameraResponseUniforms(program, {}, glm::vec3(1.0f), noise, *texture, 1);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, layer_.id());
  glUniform1i(program.uniform("u_layer"), 0);
  glUniform2f(program.uniform("u_layer_texel"), 1.0f / static_cast<float>(width_px_ * choice_.grid),
              1.0f / static_cast<float>(height_px_ * choice_.grid));
  quad_.draw(program.attribute("a_position"));
  glDisable(GL_BLEND);
  glBindTexture(GL_TEXTURE_2D, 0);
  if (add_noise) {
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, 0);
    glActiveTexture(GL_TEXTURE0);
  }
  saved_.restoreScissor();
  return gles::checkGl("EdgeLayer::composite", error);
}

}  // namespace probelight::passes
