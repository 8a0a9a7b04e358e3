#include "passes/object_bloom.hpp"

#include <algorithm>
#include <cmath>

#include "passes/layer_target.hpp"
#include "passes/object_blur.hpp"

namespace probelight::passes {

int bloomDownsampleFor(double sigma_px) {
  // 3 sigma within the taps at the layer's resolution; at least 2 (the
  // halo is smooth: a quarter of the pixels is plenty).
  const double needed = 3.0 * sigma_px / static_cast<double>(kMaxObjectBlurTaps);
  return std::clamp(static_cast<int>(std::ceil(needed)), 2, 16);
}

bool ObjectBloom::init(int width_px, int height_px, double sigma_px, const ibl::CameraTransfer& camera_transfer,
                       std::string& error) {
  if (!(sigma_px > 0.0) || !std::isfinite(sigma_px)) {
    error = "ObjectBloom: the glare's spread must be a positive number of pixels";
    return false;
  }
  width_px_ = width_px;
  height_px_ = height_px;
  sigma_px_ = sigma_px;
  camera_transfer_ = camera_transfer;
  downsample_ = bloomDownsampleFor(sigma_px);
  layer_width_ = (width_px + downsample_ - 1) / downsample_;
  layer_height_ = (height_px + downsample_ - 1) / downsample_;
  // The layer spans the frame: a layer texel is width / layer_width frame pixels.
  weights_ = objectBlurWeights(sigma_px * layer_width_ / width_px);
  programs_.clear();
  depth_ = makeDepthRenderbuffer(layer_width_, layer_height_);
  // RGB: glCopyTexSubImage2D takes it from any colour buffer (a display's
  // may have no alpha).
  auto base = gles::createTexture2D(width_px, height_px, GL_RGB, GL_UNSIGNED_BYTE, GL_NEAREST, nullptr, error);
  if (!base) return false;
  base_ = std::move(*base);
  if (!makeColourLayer(layer_width_, layer_height_, &depth_, "ObjectBloom layer", layer_, layer_framebuffer_, error) ||
      !makeColourLayer(layer_width_, layer_height_, nullptr, "ObjectBloom layer", horizontal_, horizontal_framebuffer_,
                       error))
    return false;
  glBindTexture(GL_TEXTURE_2D, 0);
  if (!quad_.init(error)) return false;
  return gles::checkGl("ObjectBloom::init", error);
}

const gles::Program* ObjectBloom::program(Pass pass, std::string& error) {
  if (auto found = programs_.find(pass); found != programs_.end()) return &found->second;
  const int taps = std::max(static_cast<int>(weights_.size()) - 1, 1);
  std::string defines = "#define TAPS " + std::to_string(taps) + "\n#define BLOOM_RANGE " +
                        std::to_string(kBloomRange) + "\n" + cameraTransferDefines(camera_transfer_);
  if (pass == Pass::kComposite) defines += "#define COMPOSITE\n";
  auto made = gles::Program::fromEmbedded("object_blur.vert", "object_bloom.frag", defines, error);
  if (!made) return nullptr;
  return &programs_.emplace(pass, std::move(*made)).first->second;
}

void ObjectBloom::beginBrightPass(const PixelRect& object_region) {
  // The halo reaches 3 sigma (the taps) past the object.
  const int reach = static_cast<int>(std::ceil(3.0 * sigma_px_)) + downsample_;
  const int left = std::max(0, object_region.x - reach), top = std::max(0, object_region.y - reach);
  const int right = std::min(width_px_, object_region.x + object_region.width + reach);
  const int bottom = std::min(height_px_, object_region.y + object_region.height + reach);
  region_ = PixelRect{left, top, std::max(0, right - left), std::max(0, bottom - top)};
  // In layer texels (rows from the bottom, as GL's window), covering it.
  const double to_layer_x = static_cast<double>(layer_width_) / width_px_;
  const double to_layer_y = static_cast<double>(layer_height_) / height_px_;
  const int layer_left = static_cast<int>(std::floor(left * to_layer_x));
  const int layer_right = std::min(layer_width_, static_cast<int>(std::ceil(right * to_layer_x)));
  const int layer_bottom = static_cast<int>(std::floor((height_px_ - bottom) * to_layer_y));
  const int layer_top = std::min(layer_height_, static_cast<int>(std::ceil((height_px_ - top) * to_layer_y)));
  layer_region_ = PixelRect{layer_left, layer_bottom, std::max(0, layer_right - layer_left),
                            std::max(0, layer_top - layer_bottom)};
  saved_.capture();
  glBindFramebuffer(GL_FRAMEBUFFER, layer_framebuffer_.id());
  glViewport(0, 0, layer_width_, layer_height_);
  glEnable(GL_SCISSOR_TEST);
  glScissor(layer_region_.x, layer_region_.y, layer_region_.width, layer_region_.height);
  glClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

bool ObjectBloom::composite(std::string& error) {
  std::vector<float> weights = weights_;
  weights.resize(static_cast<size_t>(std::max(static_cast<int>(weights_.size()) - 1, 1) + 1), 0.0f);
  const gles::Program* horizontal = program(Pass::kHorizontal, error);
  const gles::Program* composite = horizontal ? program(Pass::kComposite, error) : nullptr;
  if (composite == nullptr) {
    restore();
    return false;
  }
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  // Along rows, over the layer's region.
  glBindFramebuffer(GL_FRAMEBUFFER, horizontal_framebuffer_.id());
  glViewport(0, 0, layer_width_, layer_height_);
  glEnable(GL_SCISSOR_TEST);
  glScissor(layer_region_.x, layer_region_.y, layer_region_.width, layer_region_.height);
  horizontal->use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, layer_.id());
  glUniform1i(horizontal->uniform("u_layer"), 0);
  glUniform2f(horizontal->uniform("u_step"), 1.0f / static_cast<float>(layer_width_), 0.0f);
  glUniform1fv(horizontal->uniform("u_weight"), static_cast<GLsizei>(weights.size()), weights.data());
  quad_.draw(horizontal->attribute("a_position"));
  // The caller's framebuffer: the frame under the region copied as the base
  // (texture rows from the bottom, as the window's), then the spread light
  // added to it there.
  saved_.restore();
  const int row_from_bottom = height_px_ - region_.y - region_.height;
  if (!region_.empty()) {
    glBindTexture(GL_TEXTURE_2D, base_.id());
    glCopyTexSubImage2D(GL_TEXTURE_2D, 0, region_.x, row_from_bottom, saved_.viewport[0] + region_.x,
                        saved_.viewport[1] + row_from_bottom, region_.width, region_.height);
  }
  glEnable(GL_SCISSOR_TEST);
  glScissor(saved_.viewport[0] + region_.x, saved_.viewport[1] + row_from_bottom, region_.width, region_.height);
  composite->use();
  glBindTexture(GL_TEXTURE_2D, horizontal_.id());
  glUniform1i(composite->uniform("u_layer"), 0);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, base_.id());
  glUniform1i(composite->uniform("u_base"), 2);
  glUniform2f(composite->uniform("u_step"), 0.0f, 1.0f / static_cast<float>(layer_height_));
  glUniform1fv(composite->uniform("u_weight"), static_cast<GLsizei>(weights.size()), weights.data());
  if (camera_transfer_.curve == ibl::CameraTransfer::Curve::kGamma)
    glUniform1f(composite->uniform("u_camera_gamma"), static_cast<float>(camera_transfer_.gamma));
  quad_.draw(composite->attribute("a_position"));
  for (GLenum unit : {GL_TEXTURE2, GL_TEXTURE0}) {
    glActiveTexture(unit);
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  saved_.restoreScissor();
  return gles::checkGl("ObjectBloom::composite", error);
}

}  // namespace probelight::passes
