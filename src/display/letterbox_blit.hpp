// Showing the composed frame on a screen or window of another size: scaled
// to fit with its aspect kept, centred, black around it (KMS's screen, a
// desktop window the user resizes).
#pragma once

#include <string>

#include "gles/gl_objects.hpp"

namespace probelight {

// Where the frame lands on a screen: the largest rectangle of the frame's
// aspect inside the screen, centred, in whole pixels (GL window
// coordinates: x, y of its lower-left corner, width, height). Empty (all
// 0) when either size is not positive.
struct ScreenRect {
  int x = 0, y = 0, width = 0, height = 0;
};
ScreenRect letterboxRect(int frame_width_px, int frame_height_px, int screen_width_px, int screen_height_px);

class LetterboxBlit {
 public:
  bool init(std::string& error);
  // Into the framebuffer bound now (the screen's), cleared black, `texture`
  // (the frame, drawn in a RenderTarget: row 0 at the top) at
  // letterboxRect. LINEAR: 1:1 at the frame's own size.
  void draw(GLuint texture, int frame_width_px, int frame_height_px, int screen_width_px, int screen_height_px) const;

 private:
  gles::Program program_;
  gles::FullScreenQuad quad_;
};

}  // namespace probelight
