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

// The caller's draw target as a pass that draws into its own layer and
// then back into the caller's found it: framebuffer, viewport, clear colour
// and scissor (passes/edge_antialiasing's layer, passes/object_blur's).
struct DrawTargetState {
  GLint framebuffer = 0;
  GLint viewport[4] = {0, 0, 0, 0};
  GLfloat clear_color[4] = {0, 0, 0, 0};
  GLboolean scissor_test = GL_FALSE;
  GLint scissor_box[4] = {0, 0, 0, 0};

  void capture() {
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &framebuffer);
    glGetIntegerv(GL_VIEWPORT, viewport);
    glGetFloatv(GL_COLOR_CLEAR_VALUE, clear_color);
    scissor_test = glIsEnabled(GL_SCISSOR_TEST);
    glGetIntegerv(GL_SCISSOR_BOX, scissor_box);
  }
  void restore() const {
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(framebuffer));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    glClearColor(clear_color[0], clear_color[1], clear_color[2], clear_color[3]);
    restoreScissor();
  }
  void restoreScissor() const {
    glScissor(scissor_box[0], scissor_box[1], scissor_box[2], scissor_box[3]);
    if (scissor_test)
      glEnable(GL_SCISSOR_TEST);
    else
      glDisable(GL_SCISSOR_TEST);
  }
};

}  // namespace probelight::passes
