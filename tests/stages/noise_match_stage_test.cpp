// The noise estimate kept over frames (stages/noise_match_stage.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "stages/noise_match_stage.hpp"

namespace probelight {
namespace {

ibl::SensorNoiseReading measured(double dark_sigma, double bright_sigma) {
  ibl::SensorNoiseReading reading;
  reading.status = ibl::SensorNoiseStatus::kMeasured;
  reading.dark.mean_code = glm::dvec3(40.0);
  reading.dark.sigma_code = glm::dvec3(dark_sigma);
  reading.bright.mean_code = glm::dvec3(190.0);
  reading.bright.sigma_code = glm::dvec3(bright_sigma);
  return reading;
}

TEST(NoiseEstimateSmoother, AveragesVariancesOverFrames) {
  NoiseEstimateSmoother smoother(0.5);
  EXPECT_FALSE(smoother.has());
  smoother.add(measured(1.0, 2.0), 1.0);
  ASSERT_TRUE(smoother.has());
  EXPECT_DOUBLE_EQ(smoother.dark().sigma_code.x, 1.0);
  smoother.add(measured(3.0, 2.0), 1.0);
  // Half way in variance: (1 + 9) / 2.
  EXPECT_NEAR(smoother.dark().sigma_code.y, std::sqrt(5.0), 1e-12);
  EXPECT_NEAR(smoother.bright().sigma_code.z, 2.0, 1e-12);
  EXPECT_EQ(smoother.restarts(), 0);
}

TEST(NoiseEstimateSmoother, FramesNotMeasuredLeaveItAlone) {
  NoiseEstimateSmoother smoother(0.5);
  ibl::SensorNoiseReading too_small = measured(9.0, 9.0);
  too_small.status = ibl::SensorNoiseStatus::kTooSmall;
  smoother.add(too_small, 1.0);
  EXPECT_FALSE(smoother.has());
  smoother.add(measured(1.0, 1.0), 1.0);
  smoother.add(too_small, 1.0);
  EXPECT_DOUBLE_EQ(smoother.dark().sigma_code.x, 1.0);
}

TEST(NoiseEstimateSmoother, AGainChangeStartsAgain) {
  NoiseEstimateSmoother smoother(0.3);
  smoother.add(measured(1.0, 1.5), 2.0);
  // Within 5%: smoothed.
  smoother.add(measured(2.0, 3.0), 2.08);
  EXPECT_GT(smoother.dark().sigma_code.x, 1.0);
  EXPECT_LT(smoother.dark().sigma_code.x, 2.0);
  EXPECT_EQ(smoother.restarts(), 0);
  // Twice the gain (the last kept was 2.08): the new frame's noise at once.
  smoother.add(measured(2.0, 3.0), 4.16);
  EXPECT_DOUBLE_EQ(smoother.dark().sigma_code.x, 2.0);
  EXPECT_DOUBLE_EQ(smoother.bright().sigma_code.x, 3.0);
  EXPECT_EQ(smoother.restarts(), 1);
  // An unknown gain (0) never restarts it.
  smoother.add(measured(4.0, 4.0), 0.0);
  EXPECT_LT(smoother.dark().sigma_code.x, 4.0);
  EXPECT_EQ(smoother.restarts(), 1);
}

}  // namespace
}  // namespace probelight
