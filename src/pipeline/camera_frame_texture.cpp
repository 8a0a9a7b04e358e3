#include "pipeline/camera_frame_texture.hpp"

namespace probelight::pipeline {

bool CameraFrameTexture::init(const gles::Capabilities& capabilities, std::string& error) {
  max_texture_size_px_ = capabilities.max_texture_size_px;
  if (max_texture_size_px_ <= 0) {
    error = "CameraFrameTexture: capabilities were not probed (max texture size 0); call gles::probeCapabilities() first";
    return false;
  }
  return true;
}

bool CameraFrameTexture::upload(const ImageRGB8& image, std::string& error) {
  if (image.empty() || image.pixels.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 3u) {
    error = "CameraFrameTexture: the camera image is empty or its pixel buffer does not match " +
            std::to_string(image.width) + "x" + std::to_string(image.height) + " RGB";
    return false;
  }
  if (image.width > max_texture_size_px_ || image.height > max_texture_size_px_) {
    error = "CameraFrameTexture: camera frame " + std::to_string(image.width) + "x" + std::to_string(image.height) +
            " exceeds the GPU's maximum texture size " + std::to_string(max_texture_size_px_) +
            "; configure a smaller camera mode";
    return false;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);  // rows are tightly packed RGB
  if (image.width != width_px_ || image.height != height_px_ || !texture_.valid()) {
    auto texture = gles::createTexture2D(image.width, image.height, GL_RGB, GL_UNSIGNED_BYTE, GL_LINEAR,
                                         image.pixels.data(), error);
    if (!texture) return false;
    texture_ = std::move(*texture);
    width_px_ = image.width;
    height_px_ = image.height;
    return true;
  }
  glBindTexture(GL_TEXTURE_2D, texture_.id());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGB, GL_UNSIGNED_BYTE, image.pixels.data());
  return gles::checkGl("glTexSubImage2D(camera frame)", error);
}

}  // namespace probelight::pipeline
