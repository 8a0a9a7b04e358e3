// The ratio of two frames' camera responses (stages/frame_response.hpp):
// exact per channel where both frames say, 1 where either cannot.
#include <gtest/gtest.h>

#include <cmath>

#include "stages/frame_response.hpp"

namespace probelight {
namespace {

FrameMetadata metadata(double exposure_us, double gain, double red, double blue) {
  FrameMetadata m;
  m.exposure_us = exposure_us;
  m.analogue_gain = gain;
  m.red_gain = red;
  m.blue_gain = blue;
  return m;
}

TEST(FrameResponse, TwoStopsDownAndAWhiteBalanceMoveArePerChannelRatios) {
  const FrameResponse before = frameResponseOf(metadata(20000.0, 2.0, 1.8, 1.5));
  // Two stops down (20 ms to 5 ms at gain 2).
  const FrameResponse after = frameResponseOf(metadata(5000.0, 2.0, 2.34, 1.2));
  const glm::dvec3 ratio = responseRatio(before, after);
  EXPECT_DOUBLE_EQ(ratio.g, 0.25);
  EXPECT_DOUBLE_EQ(ratio.r, 0.25 * 2.34 / 1.8);
  EXPECT_DOUBLE_EQ(ratio.b, 0.25 * 1.2 / 1.5);
  // And back: the inverse, so a round trip changes nothing.
  const glm::dvec3 back = responseRatio(after, before);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(ratio[c] * back[c], 1.0, 1e-15);
}

TEST(FrameResponse, GainTimesTimeIsTheExposure) {
  // 10 ms at gain 4 takes what 40 ms at gain 1 takes.
  const glm::dvec3 ratio =
      responseRatio(frameResponseOf(metadata(40000.0, 1.0, 0.0, 0.0)), frameResponseOf(metadata(10000.0, 4.0, 0.0, 0.0)));
  EXPECT_DOUBLE_EQ(ratio.g, 1.0);
}

TEST(FrameResponse, WhatASourceCannotSayIsAFactorOfOne) {
  const FrameResponse unknown = frameResponseOf(FrameMetadata{});
  EXPECT_EQ(unknown.exposure_product, 0.0);
  const FrameResponse known = frameResponseOf(metadata(10000.0, 0.0, 2.0, 1.5));
  EXPECT_DOUBLE_EQ(known.exposure_product, 10000.0);  // gain unknown: 1
  for (const auto& [from, to] : {std::pair{unknown, known}, std::pair{known, unknown}, std::pair{unknown, unknown}}) {
    const glm::dvec3 ratio = responseRatio(from, to);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(ratio[c], 1.0);
  }
  // Exposure known on both sides, white balance on one only.
  const glm::dvec3 ratio = responseRatio(frameResponseOf(metadata(10000.0, 1.0, 0.0, 0.0)), known);
  EXPECT_EQ(ratio, glm::dvec3(1.0));
  // Nonsense (a negative or non-finite gain) is not a ratio.
  FrameResponse broken = known;
  broken.red_gain = std::nan("");
  broken.blue_gain = -1.0;
  const glm::dvec3 guarded = responseRatio(known, broken);
  EXPECT_EQ(guarded.r, 1.0);
  EXPECT_EQ(guarded.b, 1.0);
  EXPECT_TRUE(std::isfinite(guarded.g));
}

}  // namespace
}  // namespace probelight
