#include "gles/render_target.hpp"

#include <cstring>
#include <vector>

namespace probelight::gles {

bool RenderTarget::init(int width_px, int height_px, std::string& error, Colour colour) {
  if (width_px <= 0 || height_px <= 0) {
    error = "render target size must be positive, got " + std::to_string(width_px) + "x" + std::to_string(height_px);
    return false;
  }
  width_px_ = width_px;
  height_px_ = height_px;
  if (colour == Colour::kTexture) {
    // RGBA8 textures are core GLES2; LINEAR, for a display that scales it.
    auto texture = createTexture2D(width_px, height_px, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR, nullptr, error);
    if (!texture) return false;
    colour_texture_ = std::move(*texture);
  } else {
    // GL_RGBA8_OES is an extension; GLES2 core colour renderbuffers stop at
    // RGB565, so the colour buffer is a texture-less RGBA8 only where offered.
    color_ = Renderbuffer::create();
    glBindRenderbuffer(GL_RENDERBUFFER, color_.id());
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8_OES, width_px, height_px);
    if (!checkGl("glRenderbufferStorage(GL_RGBA8_OES)", error)) {
      error += ". The GPU lacks GL_OES_rgb8_rgba8; an 8-bit colour target is required.";
      return false;
    }
  }
  depth_ = Renderbuffer::create();
  glBindRenderbuffer(GL_RENDERBUFFER, depth_.id());
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, width_px, height_px);
  if (!checkGl("glRenderbufferStorage(GL_DEPTH_COMPONENT16)", error)) return false;
  glBindRenderbuffer(GL_RENDERBUFFER, 0);

  framebuffer_ = Framebuffer::create();
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  if (colour == Colour::kTexture)
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour_texture_.id(), 0);
  else
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_.id());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.id());
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = "render target " + std::to_string(width_px) + "x" + std::to_string(height_px) +
            " (RGBA8 + DEPTH16) is incomplete: " + framebufferStatusName(status);
    return false;
  }
  return checkGl("RenderTarget::init", error);
}

void RenderTarget::bind() const {
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, width_px_, height_px_);
}

bool RenderTarget::readRGB(ImageRGB8& image, std::string& error) const {
  // RGBA/UNSIGNED_BYTE is the one read format every GLES2 implementation accepts.
  std::vector<std::uint8_t> rgba(static_cast<size_t>(width_px_) * static_cast<size_t>(height_px_) * 4u);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_px_, height_px_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  if (!checkGl("glReadPixels(render target)", error)) return false;
  image.resize(width_px_, height_px_);
  for (int y = 0; y < height_px_; ++y) {
    // GL row 0 is the bottom of the picture.
    const std::uint8_t* source = rgba.data() + static_cast<size_t>(height_px_ - 1 - y) * static_cast<size_t>(width_px_) * 4u;
    std::uint8_t* target = image.row(y);
    for (int x = 0; x < width_px_; ++x) {
      target[3 * x + 0] = source[4 * x + 0];
      target[3 * x + 1] = source[4 * x + 1];
      target[3 * x + 2] = source[4 * x + 2];
    }
  }
  return true;
}

}  // namespace probelight::gles
