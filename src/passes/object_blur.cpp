#include "passes/object_blur.hpp"

#include <algorithm>
#include <cmath>

#include "passes/layer_target.hpp"

namespace probelight::passes {

double objectBlurSigmaPx(double frame_edge_sigma_px, double object_edge_variance_px2) {
  if (!std::isfinite(frame_edge_sigma_px)) return 0.0;
  return std::sqrt(std::max(frame_edge_sigma_px * frame_edge_sigma_px - object_edge_variance_px2, 0.0));
}

namespace {

// The sampled Gaussian of `shape` over -taps..taps, normalised; its variance.
std::vector<double> sampledGaussian(double shape, int taps, double& variance) {
  std::vector<double> weights(static_cast<size_t>(taps + 1));
  double sum = 0.0;
  for (int k = 0; k <= taps; ++k) {
    weights[static_cast<size_t>(k)] = std::exp(-0.5 * k * k / (shape * shape));
    sum += k == 0 ? weights[0] : 2.0 * weights[static_cast<size_t>(k)];
  }
  variance = 0.0;
  for (int k = 0; k <= taps; ++k) {
    weights[static_cast<size_t>(k)] /= sum;
    variance += 2.0 * k * k * weights[static_cast<size_t>(k)];
  }
  return weights;
}

}  // namespace

std::vector<float> objectBlurWeights(double sigma_px) {
  if (!(sigma_px > 0.0) || !std::isfinite(sigma_px)) return {1.0f};
  const int taps = std::clamp(static_cast<int>(std::ceil(3.0 * sigma_px)), 1, kMaxObjectBlurTaps);
  // A Gaussian sampled at whole texels has less variance than its sigma^2
  // below about a pixel (0.08 px^2 instead of 0.16 at 0.4): its shape is
  // widened until the weights' own variance is sigma^2 (bisection; the
  // variance grows with the shape), so the blur added is what was asked.
  const double wanted = sigma_px * sigma_px;
  double low = 0.05, high = 2.0 * sigma_px + 1.0, variance = 0.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (low + high);
    sampledGaussian(mid, taps, variance);
    (variance < wanted ? low : high) = mid;
  }
  const std::vector<double> weights = sampledGaussian(0.5 * (low + high), taps, variance);
  return std::vector<float>(weights.begin(), weights.end());
}

MotionSmearTaps motionSmearTaps(const glm::dvec2& smear_px) {
  const double length_px = glm::length(smear_px);
  if (!(length_px > 0.0) || !std::isfinite(length_px)) return {};
  MotionSmearTaps result;
  result.taps = std::clamp(static_cast<int>(std::ceil(0.5 * length_px)), 1, kMaxMotionSmearTaps);
  result.step_px = smear_px / static_cast<double>(2 * result.taps + 1);
  return result;
}

bool ObjectBlurLayer::init(int width_px, int height_px, const ibl::CameraTransfer& camera_transfer,
                           std::string& error) {
  width_px_ = width_px;
  height_px_ = height_px;
  camera_transfer_ = camera_transfer;
  depth_ = makeDepthRenderbuffer(width_px, height_px);
  // RGB: glCopyTexSubImage2D takes it from any colour buffer (a display's
  // may have no alpha).
  auto base = gles::createTexture2D(width_px, height_px, GL_RGB, GL_UNSIGNED_BYTE, GL_NEAREST, nullptr, error);
  if (!base) return false;
  base_ = std::move(*base);
  if (!makeColourLayer(width_px, height_px, &depth_, "ObjectBlurLayer", layer_, layer_framebuffer_, error) ||
      !makeColourLayer(width_px, height_px, nullptr, "ObjectBlurLayer", horizontal_, horizontal_framebuffer_, error))
    return false;
  glBindTexture(GL_TEXTURE_2D, 0);
  if (!quad_.init(error)) return false;
  return gles::checkGl("ObjectBlurLayer::init", error);
}

const gles::Program* ObjectBlurLayer::program(Pass pass, int taps, bool noise, std::string& error) {
  const auto key = std::make_tuple(pass, taps, noise);
  if (auto found = programs_.find(key); found != programs_.end()) return &found->second;
  std::string defines = "#define TAPS " + std::to_string(taps) + "\n" + cameraResponseDefines(camera_transfer_, noise);
  if (pass == Pass::kComposite) defines += "#define COMPOSITE\n";
  auto made = gles::Program::fromEmbedded("object_blur.vert", "object_blur.frag", defines, error);
  if (!made) return nullptr;
  return &programs_.emplace(key, std::move(*made)).first->second;
}

void ObjectBlurLayer::scissorTo(const PixelRect& rect, int viewport_x, int viewport_y) const {
  // GL's window rows count from the bottom; the rectangle's from the top.
  glScissor(viewport_x + rect.x, viewport_y + (height_px_ - rect.y - rect.height), rect.width, rect.height);
}

void ObjectBlurLayer::beginObject(const PixelRect& region, double sigma_px, const glm::dvec2& smear_px) {
  weights_ = objectBlurWeights(sigma_px);
  smear_ = motionSmearTaps(smear_px);
  // The Gaussian's taps, and the box's (its last tap, and the bilinear
  // texel past it).
  const int reach = static_cast<int>(weights_.size()) - 1;
  const int reach_x = reach + static_cast<int>(std::ceil(smear_.taps * std::abs(smear_.step_px.x))) + 1;
  const int reach_y = reach + static_cast<int>(std::ceil(smear_.taps * std::abs(smear_.step_px.y))) + 1;
  auto grown = [&](int times) {
    const int left = std::max(0, region.x - times * reach_x), top = std::max(0, region.y - times * reach_y);
    const int right = std::min(width_px_, region.x + region.width + times * reach_x);
    const int bottom = std::min(height_px_, region.y + region.height + times * reach_y);
    return PixelRect{left, top, std::max(0, right - left), std::max(0, bottom - top)};
  };
  // The layers keep earlier frames' objects outside what this frame
  // writes, and each pass reads up to the reach past what it writes: the
  // composite writes the region grown by the reach and reads the last
  // layer there grown by another; the layer passes (at most two) write
  // the region grown by three reaches, from the layer cleared over four.
  // So nothing an earlier frame left is read (a moving object's old
  // place would otherwise bleed into the new one's edge).
  region_ = grown(1);
  passes_region_ = grown(3);
  cleared_region_ = grown(4);
  saved_.capture();
  // The frame under the region, as the base (texture rows from the
  // bottom, as the window's).
  if (!region_.empty()) {
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, base_.id());
    const int row_from_bottom = height_px_ - region_.y - region_.height;
    glCopyTexSubImage2D(GL_TEXTURE_2D, 0, region_.x, row_from_bottom, saved_.viewport[0] + region_.x,
                        saved_.viewport[1] + row_from_bottom, region_.width, region_.height);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, layer_framebuffer_.id());
  glViewport(0, 0, width_px_, height_px_);
  glEnable(GL_SCISSOR_TEST);
  scissorTo(cleared_region_, 0, 0);
  glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
}

void ObjectBlurLayer::restore() {
  saved_.restore();
}

bool ObjectBlurLayer::composite(const SensorNoiseMatch* noise, const SensorNoiseTexture* noise_texture,
                                std::string& error) {
  const int taps = std::max(static_cast<int>(weights_.size()) - 1, 1);
  // A zero blur still passes through (the centre's weight 1, its
  // neighbours' 0), so that the mixing and the noise have one place.
  std::vector<float> weights = weights_;
  weights.resize(static_cast<size_t>(taps + 1), 0.0f);
  const bool add_noise = noise != nullptr && noise_texture != nullptr && noise_texture->valid();
  const gles::Program* composite = program(Pass::kComposite, taps, add_noise, error);
  if (composite == nullptr) {
    restore();
    return false;
  }
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  // With a smear: its box, layer -> horizontal; the Gaussian along rows,
  // horizontal -> layer; the composite reads the layer. Without: the
  // Gaussian along rows, layer -> horizontal; the composite reads that.
  const gles::Texture* last = &horizontal_;
  if (smear_.taps > 0) {
    const std::vector<float> box(static_cast<size_t>(smear_.taps + 1), 1.0f / static_cast<float>(2 * smear_.taps + 1));
    if (!passIntoLayer(layer_, horizontal_framebuffer_, smear_.step_px, box, error) ||
        !passIntoLayer(horizontal_, layer_framebuffer_, glm::dvec2(1.0, 0.0), weights, error)) {
      restore();
      return false;
    }
    last = &layer_;
  } else if (!passIntoLayer(layer_, horizontal_framebuffer_, glm::dvec2(1.0, 0.0), weights, error)) {
    restore();
    return false;
  }
  // The caller's framebuffer: over the region, the blurred object mixed
  // into the base.
  restore();
  glEnable(GL_SCISSOR_TEST);
  scissorTo(region_, saved_.viewport[0], saved_.viewport[1]);
  composite->use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, last->id());
  glUniform1i(composite->uniform("u_layer"), 0);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, base_.id());
  glUniform1i(composite->uniform("u_base"), 2);
  glUniform2f(composite->uniform("u_step"), 0.0f, 1.0f / static_cast<float>(height_px_));
  glUniform1fv(composite->uniform("u_weight"), static_cast<GLsizei>(weights.size()), weights.data());
  if (add_noise)
    setCameraResponseUniforms(*composite, camera_transfer_, glm::vec3(1.0f), noise, *noise_texture, 1);
  else if (camera_transfer_.curve == ibl::CameraTransfer::Curve::kGamma)
    glUniform1f(composite->uniform("u_camera_gamma"), static_cast<float>(camera_transfer_.gamma));
  quad_.draw(composite->attribute("a_position"));
  for (GLenum unit : {GL_TEXTURE2, GL_TEXTURE1, GL_TEXTURE0}) {
    glActiveTexture(unit);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  saved_.restoreScissor();
  return gles::checkGl("ObjectBlurLayer::composite", error);
}

}  // namespace probelight::passes

namespace probelight::passes {

bool ObjectBlurLayer::passIntoLayer(const gles::Texture& from, const gles::Framebuffer& to, const glm::dvec2& step_px,
                                    const std::vector<float>& weights, std::string& error) {
  const int taps = static_cast<int>(weights.size()) - 1;
  const gles::Program* pass = program(Pass::kHorizontal, taps, false, error);
  if (pass == nullptr) return false;
  glBindFramebuffer(GL_FRAMEBUFFER, to.id());
  glViewport(0, 0, width_px_, height_px_);
  glEnable(GL_SCISSOR_TEST);
  scissorTo(passes_region_, 0, 0);
  pass->use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, from.id());
  glUniform1i(pass->uniform("u_layer"), 0);
  // In texture coordinates; the layer's rows count from the bottom, as
  // the frame's NDC it was drawn with, so a step down the image is -v.
  glUniform2f(pass->uniform("u_step"), static_cast<float>(step_px.x / width_px_),
              static_cast<float>(-step_px.y / height_px_));
  glUniform1fv(pass->uniform("u_weight"), static_cast<GLsizei>(weights.size()), weights.data());
  if (camera_transfer_.curve == ibl::CameraTransfer::Curve::kGamma)
    glUniform1f(pass->uniform("u_camera_gamma"), static_cast<float>(camera_transfer_.gamma));
  quad_.draw(pass->attribute("a_position"));
  return gles::checkGl("ObjectBlurLayer::passIntoLayer", error);
}

}  // namespace probelight::passes
