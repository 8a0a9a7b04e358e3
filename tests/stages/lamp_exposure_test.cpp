// Seed D's exposure for the virtual lamp (stages/lamp_exposure.hpp): the
// brightest region's mean from an integral image equals the brute-force
// scan; the gain keeps the lit frame's brightest region where the room's
// was (or at 90% of white); and the ramp moves in stops with its time
// constant.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stages/lamp_exposure.hpp"

namespace probelight {
namespace {

TEST(LampExposure, TheBrightestWindowIsTheBruteForceScans) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat blocks(30, 40, CV_64F);
  for (int y = 0; y < blocks.rows; ++y)
    for (int x = 0; x < blocks.cols; ++x) blocks.at<double>(y, x) = unit(rng);
  blocks.at<double>(12, 17) = 30.0;  // one hot block
  for (int window : {1, 3, 5, 40}) {
    double brute = 0.0;
    const int w = std::min(window, blocks.cols), h = std::min(window, blocks.rows);
    for (int y = 0; y + h <= blocks.rows; ++y)
      for (int x = 0; x + w <= blocks.cols; ++x) {
        double sum = 0.0;
        for (int j = 0; j < h; ++j)
          for (int i = 0; i < w; ++i) sum += blocks.at<double>(y + j, x + i);
        brute = std::max(brute, sum / (w * h));
      }
    EXPECT_NEAR(brightestWindowMean(blocks, window), brute, 1e-9) << window;
  }
  EXPECT_EQ(brightestWindowMean(cv::Mat(), 4), 0.0);
}

TEST(LampExposure, OnlyTheLampsOwnLightPastWhiteDarkensTheFrame) {
  // Under white with the lamp: nothing to do.
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, 0.8, 0.9), 1.0);
  // The lamp takes a region to 1.8: back to 0.9.
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, 1.8, 0.9), 0.5);
  // A window already at white without the lamp sets the level kept.
  EXPECT_DOUBLE_EQ(lampExposureTarget(1.2, 1.5, 0.9), 0.8);
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, 0.0, 0.9), 1.0);
  EXPECT_DOUBLE_EQ(lampExposureTarget(0.5, std::nan(""), 0.9), 1.0);
}

TEST(LampExposure, TheRampMovesInStopsWithItsTimeConstant) {
  ExposureRamp ramp(0.5);
  EXPECT_DOUBLE_EQ(ramp.gain(), 1.0);
  // One time constant toward 1/4 (2 stops down): 1 - 1/e of the stops.
  ramp.moveToward(0.25, 0.5);
  EXPECT_NEAR(std::log2(ramp.gain()), -2.0 * (1.0 - std::exp(-1.0)), 1e-12);
  // Many small steps make the same path as one large one.
  ExposureRamp stepped(0.5);
  for (int i = 0; i < 50; ++i) stepped.moveToward(0.25, 0.01);
  EXPECT_NEAR(stepped.gain(), ramp.gain(), 1e-12);
  // A bad step or target leaves it.
  const double before = ramp.gain();
  ramp.moveToward(0.25, -1.0);
  ramp.moveToward(std::nan(""), 0.1);
  ramp.moveToward(0.0, 0.1);
  EXPECT_DOUBLE_EQ(ramp.gain(), before);
}

}  // namespace
}  // namespace probelight
