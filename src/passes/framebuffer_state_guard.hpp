// Restores the caller's framebuffer and viewport when a GPU pass returns, so
// that a pass rendering into its own targets leaves the frame being drawn
// as it found it.
#pragma once

#include <array>

#include <GLES2/gl2.h>

namespace probelight::passes {

class FramebufferStateGuard {
 public:
  FramebufferStateGuard() {
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &framebuffer_);
    glGetIntegerv(GL_VIEWPORT, viewport_.data());
  }
  ~FramebufferStateGuard() {
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(framebuffer_));
    glViewport(viewport_[0], viewport_[1], viewport_[2], viewport_[3]);
  }
  FramebufferStateGuard(const FramebufferStateGuard&) = delete;
  FramebufferStateGuard& operator=(const FramebufferStateGuard&) = delete;

 private:
  GLint framebuffer_ = 0;
  std::array<GLint, 4> viewport_{};
};

}  // namespace probelight::passes
