// ExposureSchedule: which exposure each frame a source makes ahead is taken at.
#include <gtest/gtest.h>

#include "capture/exposure_schedule.hpp"

namespace probelight {
namespace {

using Exposure = ExposureSchedule::ManualExposure;

double exposureAt(const ExposureSchedule& schedule, std::uint64_t index) {
  const auto exposure = schedule.at(index);
  return exposure ? exposure->exposure_us : 0.0;  // 0: the source's own
}

TEST(ExposureSchedule, ALadderStartsAfterTheFramesAlreadyMadeAndItsLastRungHolds) {
  ExposureSchedule schedule(3);
  schedule.handedOut(10);  // frames 11 and 12 are made already
  schedule.request({Exposure{1250.0, 1.0}, Exposure{156.0, 1.0}});
  EXPECT_EQ(exposureAt(schedule, 12), 0.0);
  EXPECT_EQ(exposureAt(schedule, 13), 1250.0);
  EXPECT_EQ(exposureAt(schedule, 14), 156.0);
  EXPECT_EQ(exposureAt(schedule, 40), 156.0);
  // Back to the source's own exposure, again after the frames made by then.
  schedule.handedOut(14);
  schedule.request({});
  EXPECT_EQ(exposureAt(schedule, 16), 156.0);
  EXPECT_EQ(exposureAt(schedule, 17), 0.0);
}

TEST(ExposureSchedule, ANewLadderReplacesTheRungsNotYetMadeAndClearForgetsAll) {
  ExposureSchedule schedule(3);
  schedule.request({Exposure{100.0, 1.0}, Exposure{200.0, 1.0}, Exposure{300.0, 1.0}});  // frames 3, 4, 5
  schedule.handedOut(1);
  schedule.request({Exposure{900.0, 2.0}});  // from frame 4 on
  EXPECT_EQ(exposureAt(schedule, 3), 100.0);
  EXPECT_EQ(exposureAt(schedule, 4), 900.0);
  EXPECT_EQ(schedule.at(5)->analogue_gain, 2.0);
  schedule.clear();
  EXPECT_FALSE(schedule.at(4));
  EXPECT_FALSE(schedule.at(1000));
}

}  // namespace
}  // namespace probelight
