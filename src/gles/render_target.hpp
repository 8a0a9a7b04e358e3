// Offscreen RGBA8 colour + 16-bit depth framebuffer: the frame the kiosk
// composes before it is shown or saved.
//
// Screen convention: image row v = 0 is the top of the picture. Everything
// drawn into a RenderTarget puts image row 0 at NDC y = +1 (the top of a KMS
// scan-out), and readRGB() flips GL's bottom-up rows so that row 0 of the
// returned image is the top.
#pragma once

#include <string>

#include "core/types.hpp"
#include "gles/gl_objects.hpp"

namespace probelight::gles {

class RenderTarget {
 public:
  // kTexture: the colour buffer is a texture (colourTexture()) that a
  // display samples to show the frame scaled; kRenderbuffer otherwise.
  enum class Colour { kRenderbuffer, kTexture };
  bool init(int width_px, int height_px, std::string& error, Colour colour = Colour::kRenderbuffer);
  // Binds the framebuffer and sets the viewport to its full size.
  void bind() const;
  // Reads the colour buffer into `image` (resized), top row first.
  bool readRGB(ImageRGB8& image, std::string& error) const;

  int widthPx() const { return width_px_; }
  int heightPx() const { return height_px_; }
  GLuint framebuffer() const { return framebuffer_.id(); }
  GLuint colourTexture() const { return colour_texture_.id(); }  // 0 unless Colour::kTexture

 private:
  int width_px_ = 0;
  int height_px_ = 0;
  Renderbuffer color_;
  Texture colour_texture_;
  Renderbuffer depth_;
  Framebuffer framebuffer_;
};

}  // namespace probelight::gles
