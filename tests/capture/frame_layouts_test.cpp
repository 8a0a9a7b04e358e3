// The camera layouts on the CPU (issue 17): what the simulated camera writes
// in each format (sim/camera_ycbcr, encodeSimFrame), read back by the
// pipeline's own decoding (FrameBuffer::rgbAt, luma): byte orders, YUYV's
// co-sited chroma, and the luma tag detection reads.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "capture/frame_source.hpp"
#include "capture/sim_frame_source.hpp"
#include "random_image.hpp"

namespace probelight {
namespace {

using testing::randomImage;

TEST(FrameLayouts, PackedRgbBytesAreReadInTheirFormatsOrder) {
  const ImageRGB8 image = randomImage(31, 9, 1);
  std::vector<std::uint8_t> expected_luma;
  lumaFromRgb(image, expected_luma);
  for (const PixelLayout layout : {PixelLayout::kRgb888, PixelLayout::kBgr888, PixelLayout::kXrgb8888}) {
    SCOPED_TRACE(layoutName(layout));
    FrameBuffer frame;
    encodeSimFrame(image, layout, frame);
    ASSERT_EQ(frame.layout, layout);
    EXPECT_EQ(frame.planes.stride_bytes[0], 31 * packedBytesPerPixel(layout));
    // DRM's little-endian words: RGB888 and XRGB8888 store blue first.
    const std::uint8_t* first = frame.planes.data[0];
    const std::uint8_t* source = image.row(0);
    EXPECT_EQ(first[0], layout == PixelLayout::kBgr888 ? source[0] : source[2]);
    EXPECT_EQ(frame.toRgb().pixels, image.pixels);
    const LumaView luma = frame.luma();
    ASSERT_EQ(luma.width, 31);
    for (int y = 0; y < 9; ++y)
      for (int x = 0; x < 31; ++x) ASSERT_EQ(luma.data[y * luma.stride + x], expected_luma[y * 31 + x]) << x << "," << y;
  }
}

// Pairs of pixels of one colour: YUYV's chroma, filtered [1/4, 1/2, 1/4]
// around each even pixel, is that colour's wherever the three taps share it,
// and the decoded pixels come back within the rounding of three codes (2,
// as for the 4:2:0 layouts). Odd pixels, halfway to the next pair, mix two
// colours and are left out; the odd width's last pixel repeats its own.
TEST(FrameLayouts, YuyvRoundTripsFlatPairsAndItsLumaIsItsYPrimeBytes) {
  ImageRGB8 image = randomImage(33, 5, 2);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x + 1 < 33; x += 4)  // runs of four: taps 2k-1..2k+1 inside
      for (int c = 0; c < 3; ++c)
        for (int dx = 1; dx < 4 && x + dx < 33; ++dx) image.row(y)[3 * (x + dx) + c] = image.row(y)[3 * x + c];
  FrameBuffer frame;
  encodeSimFrame(image, PixelLayout::kYuyv, frame);
  ASSERT_EQ(frame.layout, PixelLayout::kYuyv);
  EXPECT_EQ(frame.planes.stride_bytes[0], 4 * 17);  // 17 pairs, the last half empty
  std::vector<std::uint8_t> expected_luma;
  lumaFromRgb(image, expected_luma);
  const LumaView luma = frame.luma();
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 33; ++x) {
      EXPECT_EQ(luma.data[y * luma.stride + x], frame.planes.data[0][y * frame.planes.stride_bytes[0] + 2 * x]);
      // The encoder's float luma against OpenCV's 14-bit fixed point.
      EXPECT_LE(std::abs(luma.data[y * luma.stride + x] - expected_luma[y * 33 + x]), 1);
    }
  int compared = 0;
  for (int y = 0; y < 5; ++y)
    for (int x = 2; x + 1 < 33; x += 4) {  // even pixels whose taps x-1, x, x+1 share a colour
      const glm::u8vec3 decoded = frame.rgbAt(x, y);
      for (int c = 0; c < 3; ++c) EXPECT_LE(std::abs(decoded[c] - image.row(y)[3 * x + c]), 2) << x << "," << y;
      ++compared;
    }
  EXPECT_EQ(compared, 5 * 8);
}

TEST(FrameLayouts, NamesAndSizesOfEachLayout) {
  EXPECT_STREQ(layoutName(PixelLayout::kXrgb8888), "XRGB8888");
  EXPECT_EQ(planeCount(PixelLayout::kI420), 3);
  EXPECT_EQ(planeCount(PixelLayout::kYuyv), 1);
  EXPECT_TRUE(isYuv(PixelLayout::kYuyv));
  EXPECT_FALSE(isYuv(PixelLayout::kBgr888));
  EXPECT_FALSE(isPacked(PixelLayout::kNv12));
  EXPECT_EQ(packedBytesPerPixel(PixelLayout::kXrgb8888), 4);
}

}  // namespace
}  // namespace probelight
