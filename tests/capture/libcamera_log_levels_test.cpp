// The log levels libcamera is started with: its dma-buf provider's ERROR
// kept to fatal messages only where no provider can be opened.
#include "capture/libcamera_log_levels.hpp"

#include <gtest/gtest.h>

namespace probelight {
namespace {

TEST(LibcameraLogLevels, AreTheUsersOrTheFallbackWhereAProviderOpens) {
  EXPECT_EQ(libcameraLogLevels(nullptr, "*:ERROR", true), "*:ERROR");
  EXPECT_EQ(libcameraLogLevels("*:WARN", "*:ERROR", true), "*:WARN");
  EXPECT_EQ(libcameraLogLevels(nullptr, "", true), "");
}

TEST(LibcameraLogLevels, PutTheProvidersCategoryFirstWhereNoneOpens) {
  EXPECT_EQ(libcameraLogLevels(nullptr, "*:ERROR", false), "DmaBufAllocator:FATAL,*:ERROR");
  // The service's unit sets *:WARN: that stays for every other category.
  EXPECT_EQ(libcameraLogLevels("*:WARN", "*:ERROR", false), "DmaBufAllocator:FATAL,*:WARN");
  EXPECT_EQ(libcameraLogLevels(nullptr, "", false), "DmaBufAllocator:FATAL");
}

TEST(LibcameraLogLevels, LeaveASettingThatNamesTheCategoryAsItIs) {
  EXPECT_EQ(libcameraLogLevels("DmaBufAllocator:DEBUG,*:WARN", "*:ERROR", false), "DmaBufAllocator:DEBUG,*:WARN");
}

}  // namespace
}  // namespace probelight
