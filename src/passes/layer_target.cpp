#include "passes/layer_target.hpp"

namespace probelight::passes {

gles::Renderbuffer makeDepthRenderbuffer(int width_px, int height_px) {
  gles::Renderbuffer depth = gles::Renderbuffer::create();
  glBindRenderbuffer(GL_RENDERBUFFER, depth.id());
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, width_px, height_px);
  glBindRenderbuffer(GL_RENDERBUFFER, 0);
  return depth;
}

bool makeColourLayer(int width_px, int height_px, const gles::Renderbuffer* depth, const std::string& what,
                     gles::Texture& texture, gles::Framebuffer& framebuffer, std::string& error) {
  auto made = gles::createTexture2D(width_px, height_px, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR, nullptr, error);
  if (!made) return false;
  texture = std::move(*made);
  framebuffer = gles::Framebuffer::create();
  GLint previous = 0;
  glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.id());
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture.id(), 0);
  if (depth != nullptr) glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth->id());
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(previous));
  glBindTexture(GL_TEXTURE_2D, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = what + " " + std::to_string(width_px) + "x" + std::to_string(height_px) +
            " is incomplete: " + gles::framebufferStatusName(status);
    return false;
  }
  return true;
}

}  // namespace probelight::passes
