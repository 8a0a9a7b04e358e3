// The exposure-bracket merge on synthetic frames whose radiance is known
// exactly: a ramp over six decades, encoded as an 8-bit sRGB camera would at
// each exposure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "ibl/color_transfer.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_to_cube.hpp"

namespace probelight::ibl {
namespace {

// Radiance (reference exposure's linear units) of pixel x of a ramp:
// 1e-3 at the left to 1e3 at the right, the same down every column and in
// every channel.
double rampRadiance(int x, int width) { return std::pow(10.0, -3.0 + 6.0 * x / (width - 1)); }

ImageRGB8 exposeRamp(int width, int height, double ev) {
  ImageRGB8 image;
  image.resize(width, height);
  for (int x = 0; x < width; ++x) {
    const double value = std::min(1.0, rampRadiance(x, width) * std::exp2(ev));
    const auto code = static_cast<std::uint8_t>(std::lround(255.0 * linearToSrgb(value)));
    for (int y = 0; y < height; ++y)
      for (int c = 0; c < 3; ++c) image.row(y)[3 * x + c] = code;
  }
  return image;
}

TEST(HdrBracket, MergedRadianceFollowsTheRampWhereverSomeFrameMeasuredIt) {
  const int width = 600, height = 2;
  const std::vector<double> evs = {0.0, -3.0, -6.0, -9.0};
  std::vector<ImageRGB8> images;
  for (const double ev : evs) images.push_back(exposeRamp(width, height, ev));
  std::vector<BracketFrame> frames;
  for (size_t i = 0; i < evs.size(); ++i) frames.push_back({&images[i], evs[i]});
  const HdrMergeSettings settings;
  ASSERT_EQ(bracketProblem(frames), "");
  const HdrMergeResult merged = mergeBracket(frames, settings);
  ASSERT_EQ(merged.linear.width, width);
  int measured = 0, clipped = 0;
  for (int x = 0; x < width; ++x) {
    const double truth = rampRadiance(x, width);
    const double got = merged.linear.at(x, 0).g;
    // Each frame that measured this pixel (code strictly between dark and
    // clip) rounded the radiance by at most half a code step; a weighted
    // average of such values is within the largest of those relative
    // errors, whatever the weights.
    double bound = 0.0;
    bool any = false;
    for (const ImageRGB8& image : images) {
      const int code = image.row(0)[3 * x + 1];
      if (code <= settings.dark_code || code >= settings.clip_code) continue;
      any = true;
      // got / truth - 1 is largest when the truth sat half a code below.
      bound = std::max(bound, srgbToLinear(code / 255.0) / srgbToLinear((code - 0.5) / 255.0) - 1.0);
    }
    if (any) {
      EXPECT_NEAR(got / truth, 1.0, bound + 1e-6) << "x " << x << " radiance " << truth;
      EXPECT_EQ(merged.still_clipped[static_cast<size_t>(x)], 0);
      // Where the best frame shows the radiance at code >= 64 (3-stop
      // spacing guarantees one from 0.052 up to 0.955 * 2^9), the bound
      // is the 1.4% of a half step at code 64 unless a darker frame
      // joined in; the result stays within 2%.
      if (truth >= 0.052 && truth <= 0.955 * 512.0) {
        EXPECT_NEAR(got / truth, 1.0, 0.02) << truth;
      }
      ++measured;
    }
    // Beyond what even EV -9 measures: a lower bound, flagged.
    if (truth * std::exp2(-9.0) >= 1.0) {
      EXPECT_EQ(merged.still_clipped[static_cast<size_t>(x)], 1) << truth;
      EXPECT_LE(got, truth);
      ++clipped;
    }
  }
  EXPECT_GT(measured, 300);
  EXPECT_GT(clipped, 10);
}

TEST(HdrBracket, TheExposureRatioIsMeasuredFromTheFramesThemselves) {
  const ImageRGB8 reference = exposeRamp(600, 2, 0.0);
  const ImageRGB8 under3 = exposeRamp(600, 2, -3.0);
  const HdrMergeSettings settings;
  const std::optional<double> ratio = measureExposureRatio(reference, under3, settings, 100);
  ASSERT_TRUE(ratio);
  // Median of per-pixel ratios, each off by at most a code's rounding in
  // either frame (under 3% at the codes used, >= 25).
  EXPECT_NEAR(*ratio / std::exp2(-3.0), 1.0, 0.03);
  // A frame labelled EV -2 is caught: 0.125 measured is not 0.25.
  EXPECT_GT(std::abs(std::log2(*ratio) - (-2.0)), 0.5);
  // Nothing in common (one all clipped): no measurement rather than a guess.
  ImageRGB8 white = reference;
  std::fill(white.pixels.begin(), white.pixels.end(), 255);
  EXPECT_FALSE(measureExposureRatio(reference, white, settings, 100));
}

// The ratio is the median over every channel well exposed in both frames,
// exactly: the same element a sort of all of them gives (it is found by
// counting code pairs). Noisy frames, so that many distinct pairs occur.
TEST(HdrBracket, TheExposureRatioIsTheMedianOfEveryChannelsRatio) {
  ImageRGB8 reference = exposeRamp(640, 48, 0.0), shorter = exposeRamp(640, 48, -2.3);
  std::uint64_t state = 12345;
  auto jitter = [&](std::uint8_t code) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const int delta = static_cast<int>((state >> 33) % 9) - 4;
    return static_cast<std::uint8_t>(std::clamp(code + delta, 0, 255));
  };
  for (auto& code : reference.pixels) code = jitter(code);
  for (auto& code : shorter.pixels) code = jitter(code);
  const HdrMergeSettings settings;
  const int floor_code = std::max(settings.dark_code, 24);
  std::vector<double> ratios;
  for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
    const int a = reference.pixels[i], b = shorter.pixels[i];
    if (a >= settings.clip_code || b >= settings.clip_code || a <= floor_code || b <= floor_code) continue;
    ratios.push_back(decodeCameraValue(settings.camera_transfer, b / 255.0) /
                     decodeCameraValue(settings.camera_transfer, a / 255.0));
  }
  ASSERT_GT(ratios.size(), 10000u);
  std::sort(ratios.begin(), ratios.end());
  const std::optional<double> measured = measureExposureRatio(reference, shorter, settings, 100);
  ASSERT_TRUE(measured);
  EXPECT_DOUBLE_EQ(*measured, ratios[ratios.size() / 2]);
  EXPECT_NEAR(std::log2(*measured), -2.3, 0.1);
}

TEST(HdrBracket, BadBracketsAreNamed) {
  const ImageRGB8 a = exposeRamp(8, 2, 0.0), b = exposeRamp(9, 2, -3.0);
  EXPECT_NE(bracketProblem({}).find("at least one"), std::string::npos);
  EXPECT_NE(bracketProblem({{&a, 0.0}, {&b, -3.0}}).find("differ in size"), std::string::npos);
  EXPECT_NE(bracketProblem({{&a, 0.0}, {&a, std::nan("")}}).find("EV"), std::string::npos);
  EXPECT_TRUE(mergeBracket({{&a, 0.0}, {&b, -3.0}}, {}).linear.empty());
}

// The radiance image goes into the cube as the 8-bit one does (same
// directions, same bilinear sampling), without the 8-bit ceiling.
TEST(HdrBracket, RadianceImagesProjectLikeEightBitOnesAndKeepTheirRange) {
  CameraIntrinsics camera;
  camera.width_px = 160;
  camera.height_px = 120;
  camera.fx_px = camera.fy_px = 150.0;
  camera.cx_px = 79.5;
  camera.cy_px = 59.5;
  PoseCamFromWorld pose;  // camera at the origin looking down +Z of the world
  const MirrorBallView view{camera, pose, glm::dvec3(0.0, 0.0, 0.5), 0.1};
  ImageRGB8 image;
  image.resize(160, 120);
  ImageRGBF linear;
  linear.resize(160, 120);
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      const auto code = static_cast<std::uint8_t>(std::min(255, x + y));
      for (int c = 0; c < 3; ++c) image.row(y)[3 * x + c] = code;
      linear.at(x, y) = glm::vec3(static_cast<float>(srgbToLinear(code / 255.0)));
    }
  ProbeToCubeParams params;
  params.face_size = 16;
  params.probe_reflectance = 0.5;
  const CubeMapRGB from_bytes = probeImageToCubeMap(view, image, params);
  const CubeMapRGB from_linear = probeRadianceToCubeMap(view, linear, params);
  // The two differ only in the order of interpolating and decoding: the
  // sRGB curve's bend across neighbours at most 2 codes apart,
  // (2/255)^2 / 8 * max|f''| (~3) / reflectance ~ 5e-5.
  double worst = 0.0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (size_t i = 0; i < from_bytes.faces[face].size(); ++i)
      worst = std::max(worst, static_cast<double>(std::abs(from_bytes.faces[face][i].g - from_linear.faces[face][i].g)));
  EXPECT_LT(worst, 1e-3);
  // Ten times brighter radiance stays ten times brighter (no clip at 1).
  for (glm::vec3& pixel : linear.pixels) pixel *= 10.0f;
  const CubeMapRGB brighter = probeRadianceToCubeMap(view, linear, params);
  double max_value = 0.0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (size_t i = 0; i < brighter.faces[face].size(); ++i) {
      EXPECT_NEAR(brighter.faces[face][i].g, 10.0f * from_linear.faces[face][i].g, 1e-4f * (1.0f + brighter.faces[face][i].g));
      max_value = std::max(max_value, static_cast<double>(brighter.faces[face][i].g));
    }
  EXPECT_GT(max_value, 1.0 / params.probe_reflectance);
}

}  // namespace
}  // namespace probelight::ibl
