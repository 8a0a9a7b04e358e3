// Stage 1: the camera frame as a GL texture.
// Input: ImageRGB8 (sRGB bytes). Output: an RGB 2D texture, LINEAR,
// CLAMP_TO_EDGE, image row 0 at t = 0. An OpenCV pixel position p (pixel
// centres at integers) is sampled at texcoord = (p + 0.5) / size.
#pragma once

#include <string>

#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"

namespace probelight::pipeline {

class CameraFrameTexture {
 public:
  bool init(const gles::Capabilities& capabilities, std::string& error);
  // Re-allocates only when the size changes; otherwise glTexSubImage2D.
  bool upload(const ImageRGB8& image, std::string& error);

  GLuint texture() const { return texture_.id(); }
  int widthPx() const { return width_px_; }
  int heightPx() const { return height_px_; }
  bool empty() const { return width_px_ == 0; }

 private:
  int max_texture_size_px_ = 0;
  int width_px_ = 0;
  int height_px_ = 0;
  gles::Texture texture_;
};

}  // namespace probelight::pipeline
