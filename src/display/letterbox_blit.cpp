#include "display/letterbox_blit.hpp"

#include <algorithm>
#include <cmath>

namespace probelight {

namespace {

constexpr const char* kBlitVertex = R"(
attribute vec2 a_position;
varying vec2 v_texcoord;
void main() {
  v_texcoord = 0.5 * a_position + 0.5;
  gl_Position = vec4(a_position, 0.0, 1.0);
})";
constexpr const char* kBlitFragment = R"(
varying vec2 v_texcoord;
uniform sampler2D u_frame;
void main() { gl_FragColor = texture2D(u_frame, v_texcoord); })";

}  // namespace

ScreenRect letterboxRect(int frame_width_px, int frame_height_px, int screen_width_px, int screen_height_px) {
  if (frame_width_px <= 0 || frame_height_px <= 0 || screen_width_px <= 0 || screen_height_px <= 0) return {};
  // The side that limits is filled exactly; the other is rounded to the
  // nearest pixel, so the aspect is kept to half a pixel.
  ScreenRect rect;
  if (static_cast<long long>(screen_width_px) * frame_height_px <= static_cast<long long>(screen_height_px) * frame_width_px) {
    rect.width = screen_width_px;
    rect.height = std::clamp(static_cast<int>(std::lround(static_cast<double>(screen_width_px) * frame_height_px / frame_width_px)),
                             1, screen_height_px);
  } else {
    rect.height = screen_height_px;
    rect.width = std::clamp(static_cast<int>(std::lround(static_cast<double>(screen_height_px) * frame_width_px / frame_height_px)),
                            1, screen_width_px);
  }
  rect.x = (screen_width_px - rect.width) / 2;
  rect.y = (screen_height_px - rect.height) / 2;
  return rect;
}

bool LetterboxBlit::init(std::string& error) {
  auto program = gles::Program::fromSources("letterbox_blit.vert", kBlitVertex, "letterbox_blit.frag", kBlitFragment, "",
                                            error);
  if (!program || !quad_.init(error)) return false;
  program_ = std::move(*program);
  return true;
}

void LetterboxBlit::draw(GLuint texture, int frame_width_px, int frame_height_px, int screen_width_px,
                         int screen_height_px) const {
  glViewport(0, 0, screen_width_px, screen_height_px);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  const ScreenRect rect = letterboxRect(frame_width_px, frame_height_px, screen_width_px, screen_height_px);
  if (rect.width == 0) return;
  glViewport(rect.x, rect.y, rect.width, rect.height);
  program_.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, texture);
  glUniform1i(program_.uniform("u_frame"), 0);
  quad_.draw(program_.attribute("a_position"));
  glBindTexture(GL_TEXTURE_2D, 0);
}

}  // namespace probelight
