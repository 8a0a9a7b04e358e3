#include "ibl/color_transfer.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace probelight::ibl {
namespace {

TEST(ColorTransfer, KnownPointsOfTheSrgbCurve) {
  EXPECT_DOUBLE_EQ(srgbToLinear(0.0), 0.0);
  EXPECT_DOUBLE_EQ(srgbToLinear(1.0), 1.0);
  EXPECT_DOUBLE_EQ(linearToSrgb(0.0), 0.0);
  // 1.055 - 0.055 is 1 only up to one rounding step of pow().
  EXPECT_NEAR(linearToSrgb(1.0), 1.0, 1e-15);
  // Published value ((0.5 + 0.055) / 1.055)^2.4 = 0.2140411...; 6 decimals given, so 5e-7.
  EXPECT_NEAR(srgbToLinear(0.5), 0.214041, 5e-7);
  // The linear segment: 0.04045 / 12.92.
  EXPECT_NEAR(srgbToLinear(0.02), 0.02 / 12.92, 1e-15);
}

TEST(ColorTransfer, PiecesMeetAtTheBreakpoint) {
  // The standard's constants are rounded, so the two pieces meet only to
  // about 1e-7 in linear light (far below one 8-bit step, 1/255).
  EXPECT_NEAR(srgbToLinear(0.04045 - 1e-12), srgbToLinear(0.04045 + 1e-12), 1e-7);
  EXPECT_NEAR(linearToSrgb(0.0031308 - 1e-12), linearToSrgb(0.0031308 + 1e-12), 1e-7);
}

TEST(ColorTransfer, EveryEightBitCodeRoundTripsAndOrderIsKept) {
  double previous_linear = -1.0;
  for (int code = 0; code <= 255; ++code) {
    const double encoded = code / 255.0;
    const double linear = srgbToLinear(encoded);
    // The two formulas are exact inverses; only double rounding remains.
    EXPECT_NEAR(linearToSrgb(linear), encoded, 1e-12) << "code " << code;
    EXPECT_GT(linear, previous_linear) << "code " << code;
    previous_linear = linear;
  }
}

TEST(ColorTransfer, OutOfRangeInputsClampLikeAnEightBitTarget) {
  EXPECT_DOUBLE_EQ(linearToSrgb(4.0), linearToSrgb(1.0));
  EXPECT_DOUBLE_EQ(srgbToLinear(-0.5), 0.0);
}

}  // namespace
}  // namespace probelight::ibl

namespace probelight::ibl {
namespace {

TEST(CameraTransferDecode, EachCurveDecodesItsOwnEncoding) {
  const CameraTransfer srgb{};
  const CameraTransfer gamma{CameraTransfer::Curve::kGamma, 1.8};
  const CameraTransfer linear{CameraTransfer::Curve::kLinear, 0.0};
  for (double value : {0.0, 0.01, 0.2, 0.5, 0.9, 1.0}) {
    EXPECT_NEAR(decodeCameraValue(srgb, linearToSrgb(value)), value, 1e-12);
    EXPECT_NEAR(decodeCameraValue(gamma, std::pow(value, 1.0 / 1.8)), value, 1e-12);
    EXPECT_DOUBLE_EQ(decodeCameraValue(linear, value), value);
  }
  // Out-of-range inputs clamp, as the shader's clamp() does.
  EXPECT_DOUBLE_EQ(decodeCameraValue(gamma, 1.5), 1.0);
  EXPECT_DOUBLE_EQ(decodeCameraValue(srgb, -0.5), 0.0);
  // Mid-grey code 128 is 0.216 linear in sRGB but 0.289 under gamma 1.8:
  // the choice matters by a third, so a wrong default would show.
  EXPECT_GT(decodeCameraValue(gamma, 128.0 / 255.0) / decodeCameraValue(srgb, 128.0 / 255.0), 1.3);
}

}  // namespace
}  // namespace probelight::ibl

namespace probelight::ibl {
namespace {

// The table-driven 8-bit sRGB codes agree exactly with the pow-based
// expressions they replace: every code's decode, and the encode of a dense
// sweep of linear values plus each code's boundary and the doubles on
// either side of it (where a rounding difference would show).
TEST(SrgbCodes, TablesAgreeExactlyWithThePowExpressions) {
  for (int code = 0; code < 256; ++code)
    EXPECT_EQ(srgbCodeToLinear(static_cast<std::uint8_t>(code)), srgbToLinear(code / 255.0)) << code;
  auto exact = [](double linear) { return static_cast<int>(std::lround(255.0 * linearToSrgb(linear))); };
  for (int i = 0; i <= 200000; ++i) {
    const double linear = i / 200000.0;
    ASSERT_EQ(linearToSrgbCode(linear), exact(linear)) << linear;
  }
  for (int code = 1; code < 256; ++code) {
    // The boundary: halfway between two codes in sRGB, back to linear.
    const double boundary = srgbToLinear((code - 0.5) / 255.0);
    double linear = std::nextafter(std::nextafter(boundary, 0.0), 0.0);
    for (int step = 0; step < 5; ++step, linear = std::nextafter(linear, 2.0))
      ASSERT_EQ(linearToSrgbCode(linear), exact(linear)) << "code " << code << " at " << linear;
  }
  // Outside [0, 1] as linearToSrgb clamps; NaN as black.
  EXPECT_EQ(linearToSrgbCode(-1.0), 0);
  EXPECT_EQ(linearToSrgbCode(7.0), 255);
  EXPECT_EQ(linearToSrgbCode(std::nan("")), 0);
}

}  // namespace
}  // namespace probelight::ibl
