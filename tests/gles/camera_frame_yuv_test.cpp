// Stage 1 for the board camera's I420 frames: the GPU conversion (planes
// uploaded, or an imported external image) against the RGB the frame was
// made from. The I420 frames come from the simulator's own encoder
// (sim/camera_ycbcr), written apart from the decoder in core/ycbcr.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

#include <sys/mman.h>
#include <unistd.h>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <gtest/gtest.h>

#include "capture/frame_source.hpp"
#include "core/ycbcr.hpp"
#include "gles_test_support.hpp"
#include "passes/camera_frame_texture.hpp"
#include "capture/sim_frame_source.hpp"

namespace probelight {
namespace {

using test::GpuTest;

// Patches of random colours, 2x2-aligned, so that 4:2:0 chroma averaging
// loses nothing and the only differences are the codes' rounding.
ImageRGB8 flatPatchImage(int width, int height, int patch_px, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> code(0, 255);
  const int columns = (width + patch_px - 1) / patch_px, rows = (height + patch_px - 1) / patch_px;
  std::vector<std::uint8_t> colours(static_cast<std::size_t>(columns * rows * 3));
  for (auto& c : colours) c = static_cast<std::uint8_t>(code(random));
  ImageRGB8 image;
  image.resize(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        image.row(y)[3 * x + c] = colours[static_cast<std::size_t>(((y / patch_px) * columns + x / patch_px) * 3 + c)];
  return image;
}

FrameBuffer yuvFrame(const ImageRGB8& image, PixelLayout layout = PixelLayout::kI420) {
  FrameBuffer frame;
  encodeSimFrame(image, layout, frame);
  return frame;
}

// The frame texture's bytes, row 0 first (as stored).
ImageRGB8 readTexture(GLuint texture, int width, int height) {
  GLuint framebuffer = 0;
  glGenFramebuffers(1, &framebuffer);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width * height * 4));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &framebuffer);
  ImageRGB8 image;
  image.resize(width, height);
  for (std::size_t i = 0; i < static_cast<std::size_t>(width * height); ++i)
    for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = rgba[4 * i + c];
  return image;
}

int maxDifference(const ImageRGB8& a, const ImageRGB8& b) {
  int worst = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) worst = std::max(worst, std::abs(a.pixels[i] - b.pixels[i]));
  return worst;
}

// Same, over the pixels at least `margin_px` inside their patch: 4:2:0
// chroma is reconstructed by linear interpolation between block centres
// (what GL_LINEAR and the external sampler's 0.5 siting do), which blends
// neighbouring patches' colours across the one pixel next to each border.
// YUYV's co-sited chroma reaches two pixels in from the left edge (sample k
// filters pixels 2k-1..2k+1, and pixel 2k+1 reads samples k and k+1).
int maxDifferenceInsidePatches(const ImageRGB8& a, const ImageRGB8& b, int patch_px, int margin_px = 1) {
  int worst = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const int px = x % patch_px, py = y % patch_px;
      if (px < margin_px || px >= patch_px - margin_px || py < margin_px || py >= patch_px - margin_px ||
          x >= a.width - margin_px || y >= a.height - margin_px)
        continue;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(a.row(y)[3 * x + c] - b.row(y)[3 * x + c]));
    }
  return worst;
}

// Rounding the three codes to integers moves R'G'B' by at most
// 0.5 * (1 + max row sum of |Cb|,|Cr| coefficients) = 0.5 * (1 + 1.772) ~ 1.4
// codes (blue), and the 8-bit output rounds by another 0.5: 2 codes.
constexpr int kRoundingTolerance = 2;

TEST_F(GpuTest, I420AndNv12PlanesConvertToTheRgbTheyCameFrom) {
  const ImageRGB8 image = flatPatchImage(640, 480, 8, 7);
  passes::CameraFrameTexture texture;
  std::string error;
  ASSERT_TRUE(texture.init(test::sharedCapabilities(), error)) << error;
  // One texture object through both layouts (and back): the chroma plane's
  // format changes with them.
  for (const PixelLayout layout : {PixelLayout::kI420, PixelLayout::kNv12, PixelLayout::kI420}) {
    SCOPED_TRACE(layout == PixelLayout::kNv12 ? "NV12" : "I420");
    ASSERT_TRUE(texture.upload(yuvFrame(image, layout), error)) << error;
    EXPECT_EQ(texture.lastPath(), passes::FrameUploadPath::kYuvUpload);
    EXPECT_LE(maxDifferenceInsidePatches(readTexture(texture.texture(), 640, 480), image, 8), kRoundingTolerance);
  }
}

TEST_F(GpuTest, YuvConversionHoldsOnThePlain8BitPathForOddSizesAndPaddedRows) {
  // Without extensions (no GL_EXT_unpack_subimage: strided rows one by one),
  // with padded rows, and a size whose chroma planes are rounded up.
  const ImageRGB8 image = flatPatchImage(101, 37, 4, 11);
  for (const PixelLayout layout : {PixelLayout::kI420, PixelLayout::kNv12}) {
    const bool nv12 = layout == PixelLayout::kNv12;
    SCOPED_TRACE(nv12 ? "NV12" : "I420");
    const FrameBuffer tight = yuvFrame(image, layout);
    // The same planes with 64 bytes of padding per row, as cameras allocate.
    const int plane_count = planeCount(layout);
    const int row_bytes[3] = {101, nv12 ? 102 : 51, 51}, heights[3] = {37, 19, 19};
    std::vector<std::uint8_t> padded;
    int offsets[3] = {0, 0, 0};
    for (int p = 0; p < plane_count; ++p) {
      offsets[p] = static_cast<int>(padded.size());
      padded.resize(padded.size() + static_cast<std::size_t>((row_bytes[p] + 64) * heights[p]), 0xAB);
    }
    FrameBuffer strided = tight;
    for (int p = 0; p < plane_count; ++p) {
      for (int row = 0; row < heights[p]; ++row)
        std::copy_n(tight.planes.data[p] + row * tight.planes.stride_bytes[p], row_bytes[p],
                    padded.begin() + offsets[p] + row * (row_bytes[p] + 64));
      strided.planes.data[p] = padded.data() + offsets[p];
      strided.planes.stride_bytes[p] = row_bytes[p] + 64;
    }
    std::string error;
    for (const bool plain : {false, true}) {
      SCOPED_TRACE(plain ? "extensions masked" : "all extensions");
      const gles::Capabilities caps =
          plain ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities();
      passes::CameraFrameTexture texture;
      ASSERT_TRUE(texture.init(caps, error)) << error;
      ASSERT_TRUE(texture.upload(tight, error)) << error;
      const ImageRGB8 from_tight = readTexture(texture.texture(), 101, 37);
      EXPECT_LE(maxDifferenceInsidePatches(from_tight, image, 4), kRoundingTolerance);
      ASSERT_TRUE(texture.upload(strided, error)) << error;
      EXPECT_EQ(maxDifference(readTexture(texture.texture(), 101, 37), from_tight), 0) << "padding leaked in";
    }
  }
}

// A copy of `frame` whose plane rows are padded by `padding_bytes` (filled
// with 0xAB), as cameras allocate them; the copy's planes live in `storage`.
FrameBuffer withPaddedRows(const FrameBuffer& frame, int padding_bytes, std::vector<std::uint8_t>& storage) {
  const int plane_count = planeCount(frame.layout);
  const int chroma_height = (frame.height_px + 1) / 2;
  int offsets[3] = {0, 0, 0}, heights[3] = {frame.height_px, chroma_height, chroma_height};
  storage.clear();
  for (int p = 0; p < plane_count; ++p) {
    offsets[p] = static_cast<int>(storage.size());
    storage.resize(storage.size() + static_cast<std::size_t>((frame.planes.stride_bytes[p] + padding_bytes) * heights[p]),
                   0xAB);
  }
  FrameBuffer padded = frame;
  for (int p = 0; p < plane_count; ++p) {
    const int row_bytes = frame.planes.stride_bytes[p];
    for (int row = 0; row < heights[p]; ++row)
      std::copy_n(frame.planes.data[p] + row * row_bytes, row_bytes,
                  storage.begin() + offsets[p] + row * (row_bytes + padding_bytes));
    padded.planes.data[p] = storage.data() + offsets[p];
    padded.planes.stride_bytes[p] = row_bytes + padding_bytes;
  }
  return padded;
}

const PixelLayout kCameraLayouts[] = {PixelLayout::kI420,   PixelLayout::kNv12,   PixelLayout::kYuyv,
                                      PixelLayout::kRgb888, PixelLayout::kBgr888, PixelLayout::kXrgb8888};

// Every layout a camera may offer (issue 17), through the GPU, against the
// image it was encoded from: odd sizes, rows padded by a number of bytes
// that is no whole number of RGB pixels (so the packed rows go one by one
// even with GL_EXT_unpack_subimage), and without any extension.
TEST_F(GpuTest, EveryCameraLayoutConvertsToTheRgbItCameFrom) {
  const ImageRGB8 image = flatPatchImage(101, 37, 6, 13);
  for (const PixelLayout layout : kCameraLayouts) {
    SCOPED_TRACE(layoutName(layout));
    FrameBuffer frame;
    encodeSimFrame(image, layout, frame);
    std::vector<std::uint8_t> storage;
    const FrameBuffer padded = withPaddedRows(frame, 50, storage);
    for (const bool plain : {false, true}) {
      SCOPED_TRACE(plain ? "extensions masked" : "all extensions");
      passes::CameraFrameTexture texture;
      std::string error;
      ASSERT_TRUE(texture.init(plain ? test::sharedCapabilities().withoutExtensions() : test::sharedCapabilities(), error))
          << error;
      const FrameBuffer* inputs[] = {&frame, &padded};
      for (const FrameBuffer* input : inputs) {
        ASSERT_TRUE(texture.upload(*input, error)) << error;
        EXPECT_EQ(texture.lastPath(), isYuv(layout) ? passes::FrameUploadPath::kYuvUpload
                                                    : passes::FrameUploadPath::kPackedRgbUpload);
        const ImageRGB8 converted = readTexture(texture.texture(), 101, 37);
        if (isYuv(layout))
          EXPECT_LE(maxDifferenceInsidePatches(converted, image, 6, layout == PixelLayout::kYuyv ? 2 : 1),
                    kRoundingTolerance);
        else  // bytes in, bytes out: each texel's centre is sampled exactly
          EXPECT_EQ(maxDifference(converted, image), 0);
      }
    }
  }
}

// The GPU against the CPU's own decoding (FrameBuffer::toRgb, what the
// tag's border and the ball's pixels are read with) on an image with no
// flat areas: YUYV's chroma interpolation between co-sited samples and the
// packed byte orders must agree pixel for pixel, to the one code that
// float rounding on either side can move a result.
TEST_F(GpuTest, PackedLayoutsConvertOnTheGpuAsTheCpuReferenceDoes) {
  const ImageRGB8 image = flatPatchImage(67, 29, 1, 17);  // every pixel its own colour
  passes::CameraFrameTexture texture;
  std::string error;
  ASSERT_TRUE(texture.init(test::sharedCapabilities(), error)) << error;
  for (const PixelLayout layout : {PixelLayout::kYuyv, PixelLayout::kRgb888, PixelLayout::kBgr888, PixelLayout::kXrgb8888}) {
    SCOPED_TRACE(layoutName(layout));
    FrameBuffer frame;
    encodeSimFrame(image, layout, frame);
    ASSERT_TRUE(texture.upload(frame, error)) << error;
    EXPECT_LE(maxDifference(readTexture(texture.texture(), 67, 29), frame.toRgb()), layout == PixelLayout::kYuyv ? 1 : 0);
  }
}

TEST_F(GpuTest, YcbcrDecodingInvertsEachStandardsForwardEquations) {
  // Forward equations of each standard (Kr, Kb) and range, as a camera's ISP
  // applies them; the decoder must undo them to within float rounding.
  struct Case { YcbcrMatrix matrix; double kr, kb; bool full; };
  const Case cases[] = {{YcbcrMatrix::kRec601, 0.299, 0.114, true},   {YcbcrMatrix::kRec601, 0.299, 0.114, false},
                        {YcbcrMatrix::kRec709, 0.2126, 0.0722, true}, {YcbcrMatrix::kRec709, 0.2126, 0.0722, false},
                        {YcbcrMatrix::kRec2020, 0.2627, 0.0593, false}};
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Case& c : cases) {
    const YcbcrDecoding decoding = ycbcrDecoding(YcbcrEncoding{c.matrix, c.full});
    for (int trial = 0; trial < 200; ++trial) {
      const double r = unit(random), g = unit(random), b = unit(random);
      const double y = c.kr * r + (1.0 - c.kr - c.kb) * g + c.kb * b;
      const double cb = (b - y) / (2.0 * (1.0 - c.kb)), cr = (r - y) / (2.0 * (1.0 - c.kr));
      const double code[3] = {c.full ? y : (16.0 + 219.0 * y) / 255.0,
                              c.full ? cb + 128.0 / 255.0 : (128.0 + 224.0 * cb) / 255.0,
                              c.full ? cr + 128.0 / 255.0 : (128.0 + 224.0 * cr) / 255.0};
      const double expected[3] = {r, g, b};
      for (int row = 0; row < 3; ++row) {
        double value = decoding.offset[row];
        for (int column = 0; column < 3; ++column) value += decoding.matrix[column * 3 + row] * code[column];
        EXPECT_NEAR(value, expected[row], 1e-5) << YcbcrEncoding{c.matrix, c.full}.describe();
      }
    }
  }
}

// The zero-copy path's second half: an EGLImage sampled through
// samplerExternalOES into the frame texture. llvmpipe cannot import
// dmabufs, so the EGLImage here comes from a GL texture
// (EGL_KHR_gl_texture_2D_image): the same binding and shader a camera
// buffer goes through.
TEST_F(GpuTest, ExternalImagesAreCopiedIntoTheFrameTextureUnchanged) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  const EGLDisplay display = eglGetCurrentDisplay();
  const char* egl_extensions = eglQueryString(display, EGL_EXTENSIONS);
  if (!caps.egl_image_external || !egl_extensions || !std::strstr(egl_extensions, "EGL_KHR_gl_texture_2D_image"))
    GTEST_SKIP() << "this GL has no external images to test with";
  // Pretend dmabuf import exists, so that the external program is built.
  gles::Capabilities with_import = caps;
  with_import.egl_dmabuf_import = true;
  passes::CameraFrameTexture texture;
  std::string error;
  ASSERT_TRUE(texture.init(with_import, error)) << error;
  ASSERT_TRUE(texture.dmabufImportAvailable()) << texture.dmabufImportProblem();

  const ImageRGB8 image = flatPatchImage(96, 64, 1, 5);
  std::vector<std::uint8_t> rgba(96 * 64 * 4, 255);
  for (std::size_t i = 0; i < 96 * 64; ++i)
    for (int c = 0; c < 3; ++c) rgba[4 * i + c] = image.pixels[3 * i + c];
  GLuint source = 0;
  glGenTextures(1, &source);
  glBindTexture(GL_TEXTURE_2D, source);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, 96, 64, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  auto create_image = reinterpret_cast<PFNEGLCREATEIMAGEKHRPROC>(eglGetProcAddress("eglCreateImageKHR"));
  auto destroy_image = reinterpret_cast<PFNEGLDESTROYIMAGEKHRPROC>(eglGetProcAddress("eglDestroyImageKHR"));
  const EGLint attributes[] = {EGL_GL_TEXTURE_LEVEL_KHR, 0, EGL_NONE};
  const EGLImageKHR image_handle = create_image(display, eglGetCurrentContext(), EGL_GL_TEXTURE_2D_KHR,
                                                reinterpret_cast<EGLClientBuffer>(static_cast<std::uintptr_t>(source)),
                                                attributes);
  ASSERT_NE(image_handle, EGL_NO_IMAGE_KHR) << "eglCreateImageKHR: 0x" << std::hex << eglGetError();
  ASSERT_TRUE(texture.convertExternalImage(image_handle, 96, 64, error)) << error;
  // Texel centres sampled exactly: bytes in, bytes out.
  EXPECT_LE(maxDifference(readTexture(texture.texture(), 96, 64), image), 1);
  destroy_image(display, image_handle);
  glDeleteTextures(1, &source);
}

// A frame's planes put in a memfd as if it were the camera's dmabuf, at the
// offsets a camera would give them (one buffer, planes one after another);
// `buffer_bytes` may cut it short. The CPU pointers stay, as a camera's
// mapped buffer would.
struct FakeDmabuf {
  int fd = -1;
  ~FakeDmabuf() {
    if (fd >= 0) ::close(fd);
  }
};
void putPlanesInMemfd(FrameBuffer& frame, FakeDmabuf& buffer, std::size_t cut_to_bytes = 0) {
  buffer.fd = ::memfd_create("probelight-test-frame", 0);
  ASSERT_GE(buffer.fd, 0);
  std::size_t offset = 0;
  for (int p = 0; p < planeCount(frame.layout); ++p) {
    const int rows = p == 0 ? frame.height_px : (frame.height_px + 1) / 2;
    const std::size_t bytes = static_cast<std::size_t>(frame.planes.stride_bytes[p]) * static_cast<std::size_t>(rows);
    ASSERT_EQ(::pwrite(buffer.fd, frame.planes.data[p], bytes, static_cast<off_t>(offset)), static_cast<ssize_t>(bytes));
    frame.planes.dmabuf_fd[p] = buffer.fd;
    frame.planes.dmabuf_offset[p] = static_cast<std::uint32_t>(offset);
    offset += bytes;
  }
  if (cut_to_bytes) {
    ASSERT_EQ(::ftruncate(buffer.fd, static_cast<off_t>(cut_to_bytes)), 0);
  }
}

// The fallback a failed import takes: the frame converted by the upload
// path as if no dmabuf were there, the cause in one line said once, and the
// frames counted by path. Forced here by a buffer too short for its planes
// (the cause found before the driver is asked, on any driver).
TEST_F(GpuTest, AFailedDmabufImportFallsBackToTheUploadWithItsCauseInOneLine) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  if (!caps.egl_image_external) GTEST_SKIP() << "this GL has no external images: no import to fall back from";
  gles::Capabilities with_import = caps;
  with_import.egl_dmabuf_import = true;  // so that the import is tried here too
  const ImageRGB8 image = flatPatchImage(64, 48, 8, 11);
  FrameBuffer plain = yuvFrame(image, PixelLayout::kNv12);
  passes::CameraFrameTexture reference;
  std::string error;
  ASSERT_TRUE(reference.init(caps, error, false)) << error;
  ASSERT_TRUE(reference.upload(plain, error)) << error;
  const ImageRGB8 expected = readTexture(reference.texture(), 64, 48);

  passes::CameraFrameTexture texture;
  ASSERT_TRUE(texture.init(with_import, error)) << error;
  ASSERT_TRUE(texture.dmabufImportAvailable()) << texture.dmabufImportProblem();
  FrameBuffer frame = yuvFrame(image, PixelLayout::kNv12);
  FakeDmabuf buffer;
  putPlanesInMemfd(frame, buffer, 64 * 48);  // the Y plane only: the chroma rows are missing
  ASSERT_TRUE(texture.upload(frame, error)) << error;
  EXPECT_EQ(texture.lastPath(), passes::FrameUploadPath::kYuvUpload);
  EXPECT_EQ(maxDifference(readTexture(texture.texture(), 64, 48), expected), 0);
  const std::string notice = texture.takeNotice();
  EXPECT_EQ(notice.rfind("camera: dmabuf import failed: plane layout: plane 1's rows end at byte 4608", 0), 0u)
      << notice;
  EXPECT_NE(notice.find("past its dmabuf's 3072 bytes; frames take the upload path from now on"), std::string::npos)
      << notice;
  EXPECT_EQ(notice.find('\n'), std::string::npos);
  EXPECT_FALSE(texture.dmabufImportAvailable());
  EXPECT_EQ(texture.dmabufUploadReason().rfind("plane layout: plane 1", 0), 0u);

  // Said once; the next frames go straight to the upload path and are counted.
  ASSERT_TRUE(texture.upload(frame, error)) << error;
  EXPECT_EQ(texture.takeNotice(), "");
  EXPECT_EQ(texture.framesBy(passes::FrameUploadPath::kYuvUpload), 2);
  EXPECT_EQ(texture.framesBy(passes::FrameUploadPath::kDmabufImport), 0);
  EXPECT_EQ(texture.framesInDmabufs(), 2);
  EXPECT_EQ(texture.dmabufImportFallbacks(), 1);
}

// A whole buffer the driver is asked for, in each layout a camera gives
// (packed 24-bit RGB goes in as its bytes, R8). A driver that imports a
// memfd (Mesa 25's llvmpipe maps it) gives the import path, checked on its
// first frame against the upload path; one that cannot (Mesa 22's llvmpipe
// has no EGL_EXT_image_dma_buf_import) refuses it with its EGL error named,
// and the frame takes the upload path. Either way the picture is the
// frame's: packed RGB byte for byte, Y'CbCr within its rounding.
TEST_F(GpuTest, AnImportedFrameMatchesTheUploadOrFallsBackWithTheDriversReason) {
  const gles::Capabilities& caps = test::sharedCapabilities();
  if (!caps.egl_image_external) GTEST_SKIP() << "this GL has no external images";
  gles::Capabilities with_import = caps;
  with_import.egl_dmabuf_import = true;
  // 636 wide as vimc streams: rows of 1908 bytes, a multiple of 4 only.
  for (int width_px : {64, 636}) {
  for (PixelLayout layout : {PixelLayout::kNv12, PixelLayout::kI420, PixelLayout::kBgr888, PixelLayout::kRgb888}) {
    SCOPED_TRACE(std::string(layoutName(layout)) + " " + std::to_string(width_px) + " wide");
    const ImageRGB8 image = flatPatchImage(width_px, 48, 4, 12);
    passes::CameraFrameTexture texture;
    std::string error;
    ASSERT_TRUE(texture.init(with_import, error)) << error;
    FrameBuffer frame = yuvFrame(image, layout);
    FakeDmabuf buffer;
    putPlanesInMemfd(frame, buffer);
    ASSERT_TRUE(texture.upload(frame, error)) << error;
    const std::string notice = texture.takeNotice();
    if (caps.egl_dmabuf_import)
      std::printf("%s %d wide: %s\n", layoutName(layout), width_px, notice.empty() ? "imported" : notice.c_str());
    if (texture.lastPath() == passes::FrameUploadPath::kDmabufImport) {
      EXPECT_EQ(notice, "");
      ASSERT_TRUE(texture.importCheckMeanDifference().has_value());
      EXPECT_LE(*texture.importCheckMeanDifference(), isYuv(layout) ? 3.0 : 0.0);
    } else {
      EXPECT_EQ(texture.lastPath(),
                isYuv(layout) ? passes::FrameUploadPath::kYuvUpload : passes::FrameUploadPath::kPackedRgbUpload);
      EXPECT_EQ(notice.rfind("camera: dmabuf import failed: ", 0), 0u) << notice;
      EXPECT_EQ(texture.dmabufImportFallbacks(), 1);
    }
    const ImageRGB8 shown = readTexture(texture.texture(), width_px, 48);
    if (isYuv(layout)) {
      EXPECT_LE(maxDifferenceInsidePatches(shown, image, 4), kRoundingTolerance);
    } else {
      EXPECT_EQ(maxDifference(shown, image), 0);
    }
  }
  }
}

TEST_F(GpuTest, BrokenI420FramesAreRefusedWithAReason) {
  passes::CameraFrameTexture texture;
  std::string error;
  ASSERT_TRUE(texture.init(test::sharedCapabilities(), error)) << error;
  FrameBuffer frame = yuvFrame(flatPatchImage(64, 48, 2, 1));
  frame.planes.data[2] = nullptr;
  EXPECT_FALSE(texture.upload(frame, error));
  EXPECT_NE(error.find("planes"), std::string::npos) << error;
  frame = yuvFrame(flatPatchImage(64, 48, 2, 1));
  frame.planes.stride_bytes[0] = 10;  // shorter than a row
  EXPECT_FALSE(texture.upload(frame, error));
  EXPECT_NE(error.find("stride"), std::string::npos) << error;
}

}  // namespace
}  // namespace probelight
