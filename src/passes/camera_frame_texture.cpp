#include "passes/camera_frame_texture.hpp"
#include "passes/framebuffer_state_guard.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "core/ycbcr.hpp"
#include "gles/egl_context.hpp"
#include "passes/dmabuf_import_check.hpp"

#ifndef GL_UNPACK_ROW_LENGTH_EXT
#define GL_UNPACK_ROW_LENGTH_EXT 0x0CF2
#endif

namespace probelight::passes {
namespace {

// DRM fourccs, spelled out so that the pipeline does not need libdrm's
// headers: YUV420 ('YU12': planes Y, Cb, Cr), NV12 (Y, then Cb Cr pairs),
// YUYV, and the packed RGB formats (RGB888 'RG24', BGR888 'BG24', XRGB8888
// 'XR24').
constexpr EGLint fourcc(char a, char b, char c, char d) {
  return static_cast<EGLint>(static_cast<unsigned>(a) | (static_cast<unsigned>(b) << 8) |
                             (static_cast<unsigned>(c) << 16) | (static_cast<unsigned>(d) << 24));
}
EGLint drmFourccOf(PixelLayout layout) {
  switch (layout) {
    case PixelLayout::kI420: return fourcc('Y', 'U', '1', '2');
    case PixelLayout::kNv12: return fourcc('N', 'V', '1', '2');
    case PixelLayout::kYuyv: return fourcc('Y', 'U', 'Y', 'V');
    case PixelLayout::kRgb888: return fourcc('R', 'G', '2', '4');
    case PixelLayout::kBgr888: return fourcc('B', 'G', '2', '4');
    case PixelLayout::kXrgb8888: return fourcc('X', 'R', '2', '4');
    case PixelLayout::kRgb8: break;
  }
  return 0;
}

// The bytes one row of plane `plane` needs at least.
int minimumRowBytes(PixelLayout layout, int plane, int width_px) {
  const int chroma_width = (width_px + 1) / 2;
  if (layout == PixelLayout::kYuyv) return 4 * chroma_width;
  if (isPacked(layout)) return packedBytesPerPixel(layout) * width_px;
  if (plane == 0) return width_px;
  return layout == PixelLayout::kNv12 ? 2 * chroma_width : chroma_width;
}

int bytesPerTexel(GLenum format) {
  switch (format) {
    case GL_LUMINANCE_ALPHA: return 2;
    case GL_RGB: return 3;
    case GL_RGBA: return 4;
    default: return 1;
  }
}

}  // namespace

const char* toString(FrameUploadPath path) {
  switch (path) {
    case FrameUploadPath::kNone: return "none";
    case FrameUploadPath::kRgbUpload: return "rgb upload";
    case FrameUploadPath::kYuvUpload: return "yuv upload";
    case FrameUploadPath::kPackedRgbUpload: return "packed rgb upload";
    case FrameUploadPath::kDmabufImport: return "dmabuf import";
  }
  return "?";
}

CameraFrameTexture::~CameraFrameTexture() { forgetImportedBuffers(); }

bool CameraFrameTexture::init(const gles::Capabilities& capabilities, std::string& error, bool allow_dmabuf_import) {
  max_texture_size_px_ = capabilities.max_texture_size_px;
  if (max_texture_size_px_ <= 0) {
    error = "CameraFrameTexture: capabilities were not probed (max texture size 0); call gles::probeCapabilities() first";
    return false;
  }
  unpack_row_length_ = capabilities.unpack_subimage;
  auto planes = gles::Program::fromEmbedded("camera_yuv.vert", "camera_yuv_planes.frag", "", error);
  auto nv12 = gles::Program::fromEmbedded("camera_yuv.vert", "camera_yuv_planes.frag", "#define PL_NV12 1", error);
  auto yuyv = gles::Program::fromEmbedded("camera_yuv.vert", "camera_yuyv.frag", "", error);
  auto packed = gles::Program::fromEmbedded("camera_yuv.vert", "camera_packed_rgb.frag", "", error);
  auto packed_blue_first =
      gles::Program::fromEmbedded("camera_yuv.vert", "camera_packed_rgb.frag", "#define PL_BLUE_FIRST 1", error);
  if (!planes || !nv12 || !yuyv || !packed || !packed_blue_first || !quad_.init(error)) return false;
  planes_program_ = std::move(*planes);
  nv12_program_ = std::move(*nv12);
  yuyv_program_ = std::move(*yuyv);
  packed_rgb_program_ = std::move(*packed);
  packed_blue_first_program_ = std::move(*packed_blue_first);
  if (!allow_dmabuf_import)
    dmabuf_unavailable_reason_ = "zero-copy import is turned off";
  else if (!capabilities.egl_dmabuf_import)
    dmabuf_unavailable_reason_ = "EGL has no EGL_EXT_image_dma_buf_import";
  else if (!capabilities.egl_image_external)
    dmabuf_unavailable_reason_ = "GL has no GL_OES_EGL_image_external";
  if (allow_dmabuf_import && capabilities.egl_dmabuf_import && capabilities.egl_image_external) {
    display_ = eglGetCurrentDisplay();
    create_image_ = reinterpret_cast<PFNEGLCREATEIMAGEKHRPROC>(eglGetProcAddress("eglCreateImageKHR"));
    destroy_image_ = reinterpret_cast<PFNEGLDESTROYIMAGEKHRPROC>(eglGetProcAddress("eglDestroyImageKHR"));
    image_target_texture_ =
        reinterpret_cast<PFNGLEGLIMAGETARGETTEXTURE2DOESPROC>(eglGetProcAddress("glEGLImageTargetTexture2DOES"));
    std::string external_error;
    auto external = gles::Program::fromEmbedded("camera_yuv.vert", "camera_external.frag", "", external_error);
    if (display_ != EGL_NO_DISPLAY && create_image_ && destroy_image_ && image_target_texture_ && external) {
      external_program_ = std::move(*external);
      dmabuf_import_available_ = true;
      queryDriverDmabufFormats();
      // Packed 24-bit RGB is imported as bytes (R8): its texel addresses
      // need highp. Without it those frames take the upload path.
      if (capabilities.fragment_highp) {
        std::string bytes_error;
        auto bytes = gles::Program::fromEmbedded("camera_yuv.vert", "camera_external_bytes.frag", "", bytes_error);
        auto bytes_blue_first = gles::Program::fromEmbedded("camera_yuv.vert", "camera_external_bytes.frag",
                                                            "#define PL_BLUE_FIRST 1", bytes_error);
        if (bytes && bytes_blue_first) {
          external_bytes_program_ = std::move(*bytes);
          external_bytes_blue_first_program_ = std::move(*bytes_blue_first);
        }
      }
    } else {
      dmabuf_import_problem_ = external ? "EGL lacks eglCreateImageKHR or glEGLImageTargetTexture2DOES"
                                        : "the external-image shader did not compile: " + external_error;
      dmabuf_unavailable_reason_ = dmabuf_import_problem_;
    }
  }
  return true;
}

// The formats the driver says it imports, where it can say
// (EGL_EXT_image_dma_buf_import_modifiers): a format outside them is named
// as the cause before any import is tried.
void CameraFrameTexture::queryDriverDmabufFormats() {
  const char* extensions = eglQueryString(display_, EGL_EXTENSIONS);
  if (!extensions || !std::strstr(extensions, "EGL_EXT_image_dma_buf_import_modifiers")) return;
  auto query = reinterpret_cast<PFNEGLQUERYDMABUFFORMATSEXTPROC>(eglGetProcAddress("eglQueryDmaBufFormatsEXT"));
  EGLint count = 0;
  if (!query || !query(display_, 0, nullptr, &count) || count <= 0) return;
  std::vector<EGLint> formats(static_cast<std::size_t>(count));
  if (!query(display_, count, formats.data(), &count)) return;
  driver_dmabuf_formats_.emplace();
  for (EGLint i = 0; i < count; ++i) driver_dmabuf_formats_->push_back(static_cast<std::uint32_t>(formats[i]));
}

std::string CameraFrameTexture::dmabufUploadReason() const {
  if (frames_in_dmabufs_ == 0 || dmabuf_import_available_) return "";
  return dmabuf_import_problem_.empty() ? dmabuf_unavailable_reason_ : dmabuf_import_problem_;
}

std::string CameraFrameTexture::takeNotice() {
  std::string notice;
  notice.swap(notice_);
  return notice;
}

void CameraFrameTexture::giveUpImport(const std::string& cause) {
  dmabuf_import_available_ = false;
  dmabuf_import_problem_ = cause;
  ++dmabuf_import_fallbacks_;
  forgetImportedBuffers();
  notice_ = "camera: dmabuf import failed: " + cause + "; frames take the upload path from now on";
}

bool CameraFrameTexture::checkSize(int width_px, int height_px, std::string& error) const {
  if (width_px <= 0 || height_px <= 0) {
    error = "CameraFrameTexture: the camera frame is empty (" + std::to_string(width_px) + "x" + std::to_string(height_px) + ")";
    return false;
  }
  if (width_px > max_texture_size_px_ || height_px > max_texture_size_px_) {
    error = "CameraFrameTexture: camera frame " + std::to_string(width_px) + "x" + std::to_string(height_px) +
            " exceeds the GPU's maximum texture size " + std::to_string(max_texture_size_px_) +
            "; configure a smaller camera mode";
    return false;
  }
  return true;
}

bool CameraFrameTexture::upload(const FrameBuffer& frame, std::string& error) {
  if (frame.layout == PixelLayout::kRgb8) return upload(frame.rgb, error);
  if (!checkSize(frame.width_px, frame.height_px, error)) return false;
  const FramePlanes& planes = frame.planes;
  bool planes_ok = true;
  for (int p = 0; p < planeCount(frame.layout); ++p)
    planes_ok = planes_ok && planes.data[p] && planes.stride_bytes[p] >= minimumRowBytes(frame.layout, p, frame.width_px);
  if (!planes_ok) {
    error = std::string("CameraFrameTexture: the ") + layoutName(frame.layout) +
            " frame's planes are missing or their strides are shorter than a row";
    return false;
  }
  if (!ensureRenderableTexture(frame.width_px, frame.height_px, error)) return false;
  if (planes.hasDmabuf(planeCount(frame.layout))) {
    ++frames_in_dmabufs_;
    if (!dmabuf_import_available_) {
      if (frames_in_dmabufs_ == 1 && dmabuf_import_problem_.empty() && !dmabuf_unavailable_reason_.empty())
        notice_ = "camera: frames come in dmabufs, but " + dmabuf_unavailable_reason_ +
                  ": they take the upload path (a copy each)";
    } else {
      std::string import_error;
      if (importDmabuf(planes, frame.layout, frame.width_px, frame.height_px, import_error)) {
        if (!import_check_mean_difference_) return checkImportAgainstUpload(frame, error);
        last_path_ = FrameUploadPath::kDmabufImport;
        ++frames_by_path_[static_cast<std::size_t>(last_path_)];
        return true;
      }
      // The driver would not take this buffer: the upload path from now on.
      giveUpImport(import_error);
    }
  }
  return uploadByLayout(frame, error);
}

bool CameraFrameTexture::uploadByLayout(const FrameBuffer& frame, std::string& error) {
  const FramePlanes& planes = frame.planes;
  const bool uploaded = frame.layout == PixelLayout::kYuyv ? uploadYuyv(planes, frame.width_px, frame.height_px, error)
                        : isPacked(frame.layout)
                            ? uploadPackedRgb(planes, frame.layout, frame.width_px, frame.height_px, error)
                            : uploadPlanes(planes, frame.layout, frame.width_px, frame.height_px, error);
  if (!uploaded) return false;
  last_path_ = isYuv(frame.layout) ? FrameUploadPath::kYuvUpload : FrameUploadPath::kPackedRgbUpload;
  ++frames_by_path_[static_cast<std::size_t>(last_path_)];
  return true;
}

std::vector<std::uint8_t> CameraFrameTexture::readBack() const {
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width_px_) * static_cast<std::size_t>(height_px_) * 4u);
  FramebufferStateGuard saved;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_px_, height_px_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  return rgba;
}

// The imported frame (already in the texture) against the same frame
// converted by the upload path. Both decode the same 8-bit codes with the
// same matrix and range (the import through the colour-space hints) and
// write 8-bit RGB: rounding alone differs by at most one code a channel.
// The driver may place and filter the subsampled chroma otherwise than the
// upload's shader, which moves pixels at colour edges only. A mean
// difference over 3 codes is beyond both: a different matrix or range (a
// narrow range taken as full is 7-15% off), or swapped channels or planes.
bool CameraFrameTexture::checkImportAgainstUpload(const FrameBuffer& frame, std::string& error) {
  constexpr double kMaxMeanDifferenceCodes = 3.0;
  const std::vector<std::uint8_t> imported = readBack();
  if (!uploadByLayout(frame, error)) return false;
  --frames_by_path_[static_cast<std::size_t>(last_path_)];  // one frame, counted once below
  const std::vector<std::uint8_t> uploaded = readBack();
  double sum = 0.0;
  for (std::size_t i = 0; i < uploaded.size(); ++i)
    if (i % 4 != 3) sum += std::abs(static_cast<int>(imported[i]) - static_cast<int>(uploaded[i]));
  const double mean = uploaded.empty() ? 0.0 : sum / (static_cast<double>(uploaded.size()) * 0.75);
  import_check_mean_difference_ = mean;
  if (mean > kMaxMeanDifferenceCodes) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "the imported frame differs from the upload path's by %.1f codes on average (rounding stays under "
                  "%.0f): the driver converts this format otherwise",
                  mean, kMaxMeanDifferenceCodes);
    giveUpImport(text);
  } else {
    last_path_ = FrameUploadPath::kDmabufImport;
  }
  ++frames_by_path_[static_cast<std::size_t>(last_path_)];
  return true;
}

bool CameraFrameTexture::upload(const ImageRGB8& image, std::string& error) {
  if (image.pixels.size() != static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * 3u) {
    error = "CameraFrameTexture: the camera image's pixel buffer does not match " + std::to_string(image.width) + "x" +
            std::to_string(image.height) + " RGB";
    return false;
  }
  if (!checkSize(image.width, image.height, error)) return false;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);  // rows are tightly packed RGB
  last_path_ = FrameUploadPath::kRgbUpload;
  if (image.width != width_px_ || image.height != height_px_ || !texture_.valid() || renderable_) {
    auto texture = gles::createTexture2D(image.width, image.height, GL_RGB, GL_UNSIGNED_BYTE, GL_LINEAR,
                                         image.pixels.data(), error);
    if (!texture) return false;
    texture_ = std::move(*texture);
    framebuffer_ = gles::Framebuffer{};
    renderable_ = false;
    width_px_ = image.width;
    height_px_ = image.height;
    return true;
  }
  glBindTexture(GL_TEXTURE_2D, texture_.id());
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGB, GL_UNSIGNED_BYTE, image.pixels.data());
  return gles::checkGl("glTexSubImage2D(camera frame)", error);
}

bool CameraFrameTexture::ensureRenderableTexture(int width_px, int height_px, std::string& error) {
  if (renderable_ && width_px == width_px_ && height_px == height_px_) return true;
  // RGBA bytes: the one colour-renderable texture format every GLES2 GPU has.
  auto texture = gles::createTexture2D(width_px, height_px, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR, nullptr, error);
  if (!texture) return false;
  gles::Framebuffer framebuffer = gles::Framebuffer::create();
  FramebufferStateGuard saved;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.id());
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture->id(), 0);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    error = "CameraFrameTexture: cannot render the camera frame into an RGBA texture: " +
            gles::framebufferStatusName(status);
    return false;
  }
  texture_ = std::move(*texture);
  framebuffer_ = std::move(framebuffer);
  renderable_ = true;
  width_px_ = width_px;
  height_px_ = height_px;
  return true;
}

bool CameraFrameTexture::uploadPlane(gles::Texture& texture, int& allocated_width, int& allocated_height,
                                     GLenum& allocated_format, const std::uint8_t* data, int stride_bytes, int width_px,
                                     int height_px, GLenum format, std::string& error) {
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  const int bytes_per_texel = bytesPerTexel(format);
  const bool tight = stride_bytes == width_px * bytes_per_texel;
  const bool reallocate = !texture.valid() || allocated_width != width_px || allocated_height != height_px ||
                          allocated_format != format;
  if (reallocate) {
    auto created = gles::createTexture2D(width_px, height_px, format, GL_UNSIGNED_BYTE, GL_LINEAR,
                                         tight ? data : nullptr, error);
    if (!created) return false;
    texture = std::move(*created);
    allocated_width = width_px;
    allocated_height = height_px;
    allocated_format = format;
    if (tight) return true;
  }
  glBindTexture(GL_TEXTURE_2D, texture.id());
  if (tight) {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_px, height_px, format, GL_UNSIGNED_BYTE, data);
  } else if (unpack_row_length_ && stride_bytes % bytes_per_texel == 0) {
    glPixelStorei(GL_UNPACK_ROW_LENGTH_EXT, stride_bytes / bytes_per_texel);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_px, height_px, format, GL_UNSIGNED_BYTE, data);
    glPixelStorei(GL_UNPACK_ROW_LENGTH_EXT, 0);
  } else {
    // Plain GLES2 cannot skip padding, and a row length counts whole
    // texels (RGB rows padded to 64 bytes are not): one row at a time
    // (cameras pad rows to 32 or 64 bytes; the copy stays in the driver).
    for (int row = 0; row < height_px; ++row)
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, row, width_px, 1, format, GL_UNSIGNED_BYTE,
                      data + static_cast<std::size_t>(row) * static_cast<std::size_t>(stride_bytes));
  }
  return gles::checkGl("glTexSubImage2D(camera plane)", error);
}

bool CameraFrameTexture::uploadPlanes(const FramePlanes& planes, PixelLayout layout, int width_px, int height_px,
                                      std::string& error) {
  const int chroma_width = (width_px + 1) / 2, chroma_height = (height_px + 1) / 2;
  const bool nv12 = layout == PixelLayout::kNv12;
  const int widths[3] = {width_px, chroma_width, chroma_width};
  const int heights[3] = {height_px, chroma_height, chroma_height};
  // NV12's Cb Cr pairs as LUMINANCE_ALPHA: Cb in .r, Cr in .a.
  const GLenum formats[3] = {GL_LUMINANCE, nv12 ? GLenum(GL_LUMINANCE_ALPHA) : GLenum(GL_LUMINANCE), GL_LUMINANCE};
  const int plane_count = planeCount(layout);
  for (int p = 0; p < plane_count; ++p)
    if (!uploadPlane(planes_[p], plane_width_[p], plane_height_[p], plane_format_[p], planes.data[p],
                     planes.stride_bytes[p], widths[p], heights[p], formats[p], error))
      return false;
  const YcbcrDecoding decoding = ycbcrDecoding(planes.encoding);
  const gles::Program& program = nv12 ? nv12_program_ : planes_program_;
  program.use();
  for (int p = 0; p < plane_count; ++p) {
    glActiveTexture(GL_TEXTURE0 + p);
    glBindTexture(GL_TEXTURE_2D, planes_[p].id());
  }
  glUniform1i(program.uniform("u_luma"), 0);
  glUniform1i(program.uniform("u_cb"), 1);
  glUniform1i(program.uniform("u_cr"), nv12 ? 1 : 2);
  glUniform2f(program.uniform("u_chroma_scale"), static_cast<float>(width_px) / (2.0f * chroma_width),
              static_cast<float>(height_px) / (2.0f * chroma_height));
  glUniformMatrix3fv(program.uniform("u_ycbcr_to_rgb"), 1, GL_FALSE, decoding.matrix);
  glUniform3fv(program.uniform("u_offset"), 1, decoding.offset);
  const bool drawn = drawIntoTexture(program, error);
  glActiveTexture(GL_TEXTURE0);
  return drawn;
}

bool CameraFrameTexture::uploadYuyv(const FramePlanes& planes, int width_px, int height_px, std::string& error) {
  // The same bytes twice: a texel a pixel (Y' in .r) and a texel a pair.
  const int pair_count = (width_px + 1) / 2;
  if (!uploadPlane(planes_[0], plane_width_[0], plane_height_[0], plane_format_[0], planes.data[0],
                   planes.stride_bytes[0], width_px, height_px, GL_LUMINANCE_ALPHA, error) ||
      !uploadPlane(planes_[1], plane_width_[1], plane_height_[1], plane_format_[1], planes.data[0],
                   planes.stride_bytes[0], pair_count, height_px, GL_RGBA, error))
    return false;
  const YcbcrDecoding decoding = ycbcrDecoding(planes.encoding);
  yuyv_program_.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, planes_[0].id());
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, planes_[1].id());
  glUniform1i(yuyv_program_.uniform("u_luma"), 0);
  glUniform1i(yuyv_program_.uniform("u_pairs"), 1);
  // Pixel i (texcoord u = (i + 0.5) / w) reads chroma at i / 2 samples,
  // texcoord (i / 2 + 0.5) / pairs = u * w / (2 pairs) + 0.25 / pairs.
  glUniform2f(yuyv_program_.uniform("u_chroma_scale"), static_cast<float>(width_px) / (2.0f * pair_count), 1.0f);
  glUniform2f(yuyv_program_.uniform("u_chroma_offset"), 0.25f / static_cast<float>(pair_count), 0.0f);
  glUniformMatrix3fv(yuyv_program_.uniform("u_ycbcr_to_rgb"), 1, GL_FALSE, decoding.matrix);
  glUniform3fv(yuyv_program_.uniform("u_offset"), 1, decoding.offset);
  const bool drawn = drawIntoTexture(yuyv_program_, error);
  glActiveTexture(GL_TEXTURE0);
  return drawn;
}

bool CameraFrameTexture::uploadPackedRgb(const FramePlanes& planes, PixelLayout layout, int width_px, int height_px,
                                         std::string& error) {
  const GLenum format = layout == PixelLayout::kXrgb8888 ? GLenum(GL_RGBA) : GLenum(GL_RGB);
  if (!uploadPlane(planes_[0], plane_width_[0], plane_height_[0], plane_format_[0], planes.data[0],
                   planes.stride_bytes[0], width_px, height_px, format, error))
    return false;
  const gles::Program& program = layout == PixelLayout::kBgr888 ? packed_rgb_program_ : packed_blue_first_program_;
  program.use();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, planes_[0].id());
  glUniform1i(program.uniform("u_packed"), 0);
  return drawIntoTexture(program, error);
}

bool CameraFrameTexture::drawIntoTexture(const gles::Program& program, std::string& error) {
  FramebufferStateGuard saved;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
  glViewport(0, 0, width_px_, height_px_);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  quad_.draw(program.attribute("a_position"));
  return gles::checkGl("camera frame conversion pass", error);
}

bool CameraFrameTexture::convertExternalImage(EGLImageKHR image, int width_px, int height_px, std::string& error) {
  return drawExternalImage(image, external_program_, GL_LINEAR, width_px, height_px, error);
}

bool CameraFrameTexture::drawExternalImage(EGLImageKHR image, const gles::Program& program, GLint filter,
                                           int width_px, int height_px, std::string& error) {
  if (!image_target_texture_ || !program.valid()) {
    error = "CameraFrameTexture: external images are not available (" +
            (dmabuf_import_problem_.empty() ? std::string("no GL_OES_EGL_image_external or dmabuf import")
                                            : dmabuf_import_problem_) +
            ")";
    return false;
  }
  if (!checkSize(width_px, height_px, error) || !ensureRenderableTexture(width_px, height_px, error)) return false;
  if (!external_texture_.valid()) external_texture_ = gles::Texture::create();
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_EXTERNAL_OES, external_texture_.id());
  glTexParameteri(GL_TEXTURE_EXTERNAL_OES, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_EXTERNAL_OES, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_EXTERNAL_OES, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_EXTERNAL_OES, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  image_target_texture_(GL_TEXTURE_EXTERNAL_OES, static_cast<GLeglImageOES>(image));
  if (!gles::checkGl("glEGLImageTargetTexture2DOES", error)) return false;
  program.use();
  if (&program == &external_program_) {
    glUniform1i(program.uniform("u_image"), 0);
  } else {
    glUniform1i(program.uniform("u_bytes"), 0);
    glUniform1f(program.uniform("u_width_px"), static_cast<GLfloat>(width_px));
  }
  const bool drawn = drawIntoTexture(program, error);
  glBindTexture(GL_TEXTURE_EXTERNAL_OES, 0);
  return drawn;
}

bool CameraFrameTexture::importDmabuf(const FramePlanes& planes, PixelLayout layout, int width_px, int height_px,
                                      std::string& error) {
  if (width_px != imported_width_px_ || height_px != imported_height_px_) forgetImportedBuffers();
  imported_width_px_ = width_px;
  imported_height_px_ = height_px;
  // Packed 24-bit RGB goes in as its bytes (R8, three texels a pixel):
  // drivers that take no 24-bit RGB buffer (Mesa's llvmpipe refuses BG24
  // with EGL_BAD_MATCH) take R8, and the bytes pass converts them.
  const bool as_bytes = layout == PixelLayout::kRgb888 || layout == PixelLayout::kBgr888;
  const gles::Program& program = !as_bytes                        ? external_program_
                                 : layout == PixelLayout::kBgr888 ? external_bytes_program_
                                                                  : external_bytes_blue_first_program_;
  if (as_bytes && !program.valid()) {
    error = std::string(layoutName(layout)) + " is imported as bytes, which needs highp in fragment shaders; " +
            "this GPU has none";
    return false;
  }
  const EGLint import_fourcc = as_bytes ? fourcc('R', '8', ' ', ' ') : drmFourccOf(layout);
  const EGLint import_width = as_bytes ? 3 * width_px : width_px;
  EGLImageKHR image = EGL_NO_IMAGE_KHR;
  for (const ImportedBuffer& imported : imported_)
    if (planes.buffer_id != 0 && imported.buffer_id == planes.buffer_id) image = imported.image;
  if (image == EGL_NO_IMAGE_KHR) {
    const YcbcrEncoding& encoding = planes.encoding;
    const EGLint color_space = encoding.matrix == YcbcrMatrix::kRec601   ? EGL_ITU_REC601_EXT
                               : encoding.matrix == YcbcrMatrix::kRec709 ? EGL_ITU_REC709_EXT
                                                                         : EGL_ITU_REC2020_EXT;
    std::vector<EGLint> attributes = {EGL_WIDTH, import_width, EGL_HEIGHT, height_px, EGL_LINUX_DRM_FOURCC_EXT,
                                      import_fourcc};
    const EGLint plane_keys[3][3] = {
        {EGL_DMA_BUF_PLANE0_FD_EXT, EGL_DMA_BUF_PLANE0_OFFSET_EXT, EGL_DMA_BUF_PLANE0_PITCH_EXT},
        {EGL_DMA_BUF_PLANE1_FD_EXT, EGL_DMA_BUF_PLANE1_OFFSET_EXT, EGL_DMA_BUF_PLANE1_PITCH_EXT},
        {EGL_DMA_BUF_PLANE2_FD_EXT, EGL_DMA_BUF_PLANE2_OFFSET_EXT, EGL_DMA_BUF_PLANE2_PITCH_EXT}};
    for (int p = 0; p < planeCount(layout); ++p)
      attributes.insert(attributes.end(), {plane_keys[p][0], planes.dmabuf_fd[p], plane_keys[p][1],
                                           static_cast<EGLint>(planes.dmabuf_offset[p]), plane_keys[p][2],
                                           planes.stride_bytes[p]});
    // The colour-space hints are for Y'CbCr buffers only. 4:2:0 chroma is
    // centre-sited; YUYV's sits on its first pixel (horizontally 0).
    if (isYuv(layout))
      attributes.insert(attributes.end(),
                        {EGL_YUV_COLOR_SPACE_HINT_EXT, color_space, EGL_SAMPLE_RANGE_HINT_EXT,
                         encoding.full_range ? EGL_YUV_FULL_RANGE_EXT : EGL_YUV_NARROW_RANGE_EXT,
                         EGL_YUV_CHROMA_HORIZONTAL_SITING_HINT_EXT,
                         layout == PixelLayout::kYuyv ? EGL_YUV_CHROMA_SITING_0_EXT : EGL_YUV_CHROMA_SITING_0_5_EXT,
                         EGL_YUV_CHROMA_VERTICAL_SITING_HINT_EXT, EGL_YUV_CHROMA_SITING_0_5_EXT});
    attributes.push_back(EGL_NONE);
    // What the buffer and the driver's list already tell, before asking.
    std::vector<DmabufPlaneLayout> plane_layouts;
    for (int p = 0; p < planeCount(layout); ++p) {
      DmabufPlaneLayout plane;
      plane.offset_bytes = planes.dmabuf_offset[p];
      plane.pitch_bytes = planes.stride_bytes[p];
      plane.row_bytes = minimumRowBytes(layout, p, width_px);
      plane.rows = (p > 0 && layout != PixelLayout::kYuyv) ? (height_px + 1) / 2 : height_px;
      const off_t size = ::lseek(planes.dmabuf_fd[p], 0, SEEK_END);
      if (size > 0)
        plane.buffer_size_bytes = static_cast<std::uint64_t>(size);
      else
        plane.buffer_size_errno = size < 0 ? errno : 0;
      ::lseek(planes.dmabuf_fd[p], 0, SEEK_SET);
      plane_layouts.push_back(plane);
    }
    const std::string obstacle =
        dmabufImportObstacle(static_cast<std::uint32_t>(import_fourcc), plane_layouts, driver_dmabuf_formats_);
    if (!obstacle.empty()) {
      error = obstacle;
      return false;
    }
    image = create_image_(display_, EGL_NO_CONTEXT, EGL_LINUX_DMA_BUF_EXT, nullptr, attributes.data());
    if (image == EGL_NO_IMAGE_KHR) {
      const EGLint egl_error = eglGetError();
      // A software renderer maps the buffer itself: whether the CPU can is
      // the first thing to know when it refuses.
      for (int p = 0; p < planeCount(layout); ++p) {
        if (!plane_layouts[p].buffer_size_bytes) continue;
        const std::size_t size = static_cast<std::size_t>(*plane_layouts[p].buffer_size_bytes);
        void* mapped = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, planes.dmabuf_fd[p], 0);
        plane_layouts[p].cpu_mapping_errno = mapped == MAP_FAILED ? errno : 0;
        if (mapped != MAP_FAILED) ::munmap(mapped, size);
      }
      error = std::string(layoutName(layout)) + " " + std::to_string(width_px) + "x" + std::to_string(height_px) +
              ": " + eglImportRefusalCause(egl_error, plane_layouts);
      // kms_swrast hands the buffer to the KMS driver's own import (PRIME),
      // where swrast and hardware drivers differ: the driver is part of why.
      if (const std::string driver = gles::displayDriverName(display_); !driver.empty())
        error += "; EGL driver " + driver;
      return false;
    }
    if (planes.buffer_id != 0) imported_.push_back(ImportedBuffer{planes.buffer_id, image});
  }
  const bool converted =
      drawExternalImage(image, program, as_bytes ? GL_NEAREST : GL_LINEAR, width_px, height_px, error);
  if (planes.buffer_id == 0) destroy_image_(display_, image);  // not a camera buffer: no reuse
  return converted;
}

void CameraFrameTexture::forgetImportedBuffers() {
  for (const ImportedBuffer& imported : imported_)
    if (destroy_image_) destroy_image_(display_, imported.image);
  imported_.clear();
}

}  // namespace probelight::passes
