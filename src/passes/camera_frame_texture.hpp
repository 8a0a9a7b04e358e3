// Stage 1: the camera frame as a GL texture.
// Input: a FrameBuffer: sRGB bytes (simulated RGB, image files, decoded
// MJPEG), or a camera's planes: I420, NV12 or YUYV Y'CbCr, or packed RGB
// (RGB888, BGR888, XRGB8888). Output: one 2D texture of sRGB bytes, LINEAR,
// CLAMP_TO_EDGE, image row 0 at t = 0, that every later stage samples. An
// OpenCV pixel position p (pixel centres at integers) is sampled at
// texcoord = (p + 0.5) / size.
//
// Camera frames take one of two paths to it:
//  - dmabuf import (zero-copy): when the planes live in a camera dmabuf and
//    EGL has EGL_EXT_image_dma_buf_import and GL has
//    GL_OES_EGL_image_external, the buffer is imported once as an EGLImage
//    (cached per camera buffer) with the stream's colour-space hints, and a
//    pass samples it as samplerExternalOES into the RGB texture; packed
//    24-bit RGB is imported as its bytes (R8) and put together by the pass;
//  - upload: the planes as LUMINANCE (NV12's Cb Cr pairs as
//    LUMINANCE_ALPHA) textures, converted by a pass with the stream's matrix
//    and range (core/ycbcr.hpp); YUYV's one plane as two views of the same
//    bytes; packed RGB as RGB (RGBA) bytes, put in R, G, B order by a pass.
// A failed import falls back to the upload path for good, with its cause
// said once in one line (passes/dmabuf_import_check.hpp). The first frame
// imported is also taken the upload path's way and the two compared: a
// driver that imports but converts differently is a failed import too.
#pragma once

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture/frame_source.hpp"
#include "core/types.hpp"
#include "gles/capabilities.hpp"
#include "gles/gl_objects.hpp"

namespace probelight::passes {

enum class FrameUploadPath { kNone, kRgbUpload, kYuvUpload, kPackedRgbUpload, kDmabufImport };
const char* toString(FrameUploadPath path);

class CameraFrameTexture {
 public:
  CameraFrameTexture() = default;
  ~CameraFrameTexture();
  CameraFrameTexture(const CameraFrameTexture&) = delete;
  CameraFrameTexture& operator=(const CameraFrameTexture&) = delete;

  // Needs a current context. `allow_dmabuf_import` false keeps I420 frames
  // on the upload path (configuration, or tests of that path).
  bool init(const gles::Capabilities& capabilities, std::string& error, bool allow_dmabuf_import = true);
  // Any frame: dispatches on its layout. Re-allocates only when the size or
  // layout changes.
  bool upload(const FrameBuffer& frame, std::string& error);
  // An RGB image (glTexSubImage2D into an RGB texture).
  bool upload(const ImageRGB8& image, std::string& error);
  // The external-image pass on its own, for an EGLImage imported elsewhere
  // (tests feed it an EGLImage made from a GL texture: llvmpipe cannot
  // import dmabufs, but samples external images the same way).
  bool convertExternalImage(EGLImageKHR image, int width_px, int height_px, std::string& error);

  GLuint texture() const { return texture_.id(); }
  int widthPx() const { return width_px_; }
  int heightPx() const { return height_px_; }
  bool empty() const { return width_px_ == 0; }
  // How the last frame got here.
  FrameUploadPath lastPath() const { return last_path_; }
  bool dmabufImportAvailable() const { return dmabuf_import_available_; }
  // Why dmabuf import was given up (empty while it works or was never tried).
  const std::string& dmabufImportProblem() const { return dmabuf_import_problem_; }
  // Why frames in dmabufs take the upload path, where any came: the import
  // given up, or what the GPU lacks for it. Empty otherwise.
  std::string dmabufUploadReason() const;
  // Frames converted by each path since init (indexed by FrameUploadPath),
  // frames that came in dmabufs, and imports given up (0 or 1).
  long long framesBy(FrameUploadPath path) const { return frames_by_path_[static_cast<std::size_t>(path)]; }
  long long framesInDmabufs() const { return frames_in_dmabufs_; }
  long long dmabufImportFallbacks() const { return dmabuf_import_fallbacks_; }
  // The first imported frame against the upload path: mean absolute
  // difference of the RGB codes (nullopt before one was compared).
  std::optional<double> importCheckMeanDifference() const { return import_check_mean_difference_; }
  // The one line to say once, when the path of camera frames changed for a
  // reason a person should know (an import failed, or frames in dmabufs
  // cannot be imported here); empty when there is none. Taking it clears it.
  std::string takeNotice();

 private:
  struct ImportedBuffer {
    std::uint64_t buffer_id = 0;
    EGLImageKHR image = EGL_NO_IMAGE_KHR;
  };
  bool checkSize(int width_px, int height_px, std::string& error) const;
  bool ensureRenderableTexture(int width_px, int height_px, std::string& error);
  bool uploadPlanes(const FramePlanes& planes, PixelLayout layout, int width_px, int height_px, std::string& error);
  bool uploadYuyv(const FramePlanes& planes, int width_px, int height_px, std::string& error);
  bool uploadPackedRgb(const FramePlanes& planes, PixelLayout layout, int width_px, int height_px, std::string& error);
  bool uploadPlane(gles::Texture& texture, int& allocated_width, int& allocated_height, GLenum& allocated_format,
                   const std::uint8_t* data, int stride_bytes, int width_px, int height_px, GLenum format,
                   std::string& error);
  // True when imported; false with `error` empty when the frame cannot be
  // imported (no dmabuf), false with `error` set when an import failed.
  bool importDmabuf(const FramePlanes& planes, PixelLayout layout, int width_px, int height_px, std::string& error);
  void forgetImportedBuffers();
  // An EGLImage sampled by `program` (filtered by `filter`) into the frame texture.
  bool drawExternalImage(EGLImageKHR image, const gles::Program& program, GLint filter, int width_px, int height_px,
                         std::string& error);
  // Draws `program` over the whole output texture.
  bool drawIntoTexture(const gles::Program& program, std::string& error);

  int max_texture_size_px_ = 0;
  int width_px_ = 0;
  int height_px_ = 0;
  bool renderable_ = false;  // texture_ is RGBA with a framebuffer (the YUV paths)
  gles::Texture texture_;
  gles::Framebuffer framebuffer_;
  FrameUploadPath last_path_ = FrameUploadPath::kNone;

  gles::Program planes_program_;  // I420: three LUMINANCE planes
  gles::Program nv12_program_;    // NV12: LUMINANCE + LUMINANCE_ALPHA
  gles::Program yuyv_program_;    // YUYV: LUMINANCE_ALPHA + RGBA views of one plane
  gles::Program packed_rgb_program_;         // BGR888: R, G, B bytes
  gles::Program packed_blue_first_program_;  // RGB888, XRGB8888: B, G, R bytes
  gles::Program external_program_;
  gles::Program external_bytes_program_;             // BGR888 imported as R8: R, G, B bytes
  gles::Program external_bytes_blue_first_program_;  // RGB888 imported as R8: B, G, R bytes
  gles::FullScreenQuad quad_;
  gles::Texture planes_[3];
  int plane_width_[3] = {0, 0, 0};
  int plane_height_[3] = {0, 0, 0};
  GLenum plane_format_[3] = {0, 0, 0};
  bool unpack_row_length_ = false;  // GL_EXT_unpack_subimage: strided rows in one call

  // The upload path for a frame in dmabufs, after a failed import.
  bool uploadDmabufFrame(const FrameBuffer& frame, std::string& error);
  bool uploadByLayout(const FrameBuffer& frame, std::string& error);
  // The first imported frame converted again by the upload path; false (and
  // the import given up) when the two differ beyond rounding.
  bool checkImportAgainstUpload(const FrameBuffer& frame, std::string& error);
  std::vector<std::uint8_t> readBack() const;
  void giveUpImport(const std::string& cause);
  void queryDriverDmabufFormats();

  bool dmabuf_import_available_ = false;
  std::string dmabuf_import_problem_;
  std::string dmabuf_unavailable_reason_;  // what the GPU or configuration lacks
  std::optional<std::vector<std::uint32_t>> driver_dmabuf_formats_;
  std::array<long long, 5> frames_by_path_{};
  long long frames_in_dmabufs_ = 0;
  long long dmabuf_import_fallbacks_ = 0;
  std::optional<double> import_check_mean_difference_;
  std::string notice_;
  EGLDisplay display_ = EGL_NO_DISPLAY;
  gles::Texture external_texture_;
  std::vector<ImportedBuffer> imported_;
  int imported_width_px_ = 0, imported_height_px_ = 0;
  PFNEGLCREATEIMAGEKHRPROC create_image_ = nullptr;
  PFNEGLDESTROYIMAGEKHRPROC destroy_image_ = nullptr;
  PFNGLEGLIMAGETARGETTEXTURE2DOESPROC image_target_texture_ = nullptr;
};

}  // namespace probelight::passes
