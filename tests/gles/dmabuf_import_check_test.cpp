// The causes a failed dmabuf import is said with: each named from what the
// buffer and the driver declare, or from the driver's EGL error.
#include "passes/dmabuf_import_check.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>

namespace probelight::passes {
namespace {

constexpr std::uint32_t code(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(a) | (static_cast<std::uint32_t>(b) << 8) | (static_cast<std::uint32_t>(c) << 16) |
         (static_cast<std::uint32_t>(d) << 24);
}
constexpr std::uint32_t kNv12 = code('N', 'V', '1', '2');
constexpr std::uint32_t kYuyv = code('Y', 'U', 'Y', 'V');
constexpr std::uint32_t kBgr888 = code('B', 'G', '2', '4');

// NV12 640x480 in one buffer: Y rows of 640 at pitch 640, then 240 rows of
// 640 bytes of Cb Cr pairs at offset 640 * 480.
std::vector<DmabufPlaneLayout> nv12Planes(std::uint64_t buffer_size) {
  return {{0, 640, 640, 480, buffer_size}, {640u * 480u, 640, 640, 240, buffer_size}};
}

TEST(DmabufImportCheck, NamesFourccCodes) {
  EXPECT_EQ(fourccName(kNv12), "NV12");
  EXPECT_EQ(fourccName(kBgr888), "BG24");
  EXPECT_EQ(fourccName(0x00323159u), "Y12?");
}

TEST(DmabufImportCheck, AFrameThatFitsItsBufferHasNoObstacle) {
  const std::uint64_t exact = 640u * 480u * 3u / 2u;
  EXPECT_EQ(dmabufImportObstacle(kNv12, nv12Planes(exact), std::nullopt), "");
  EXPECT_EQ(dmabufImportObstacle(kNv12, nv12Planes(exact), std::vector<std::uint32_t>{kYuyv, kNv12}), "");
  // Unknown sizes (an fd that cannot seek) are not held against it.
  std::vector<DmabufPlaneLayout> unknown = nv12Planes(0);
  for (DmabufPlaneLayout& plane : unknown) plane.buffer_size_bytes.reset();
  EXPECT_EQ(dmabufImportObstacle(kNv12, unknown, std::nullopt), "");
}

TEST(DmabufImportCheck, AFormatTheDriverDoesNotListIsTheCause) {
  const std::string cause = dmabufImportObstacle(kBgr888, {{0, 1920, 1920, 480, 1920u * 480u}},
                                                 std::vector<std::uint32_t>{kNv12, kYuyv});
  EXPECT_EQ(cause, "format: the driver imports no BG24 dmabufs (it offers NV12 YUYV)");
}

TEST(DmabufImportCheck, APlaneThatEndsPastItsBufferIsTheCause) {
  // One byte short: the last chroma row ends at exactly 640*480*3/2.
  const std::uint64_t exact = 640u * 480u * 3u / 2u;
  const std::string cause = dmabufImportObstacle(kNv12, nv12Planes(exact - 1), std::nullopt);
  EXPECT_EQ(cause.rfind("plane layout: plane 1's rows end at byte 460800", 0), 0u) << cause;
  EXPECT_NE(cause.find("past its dmabuf's 460799 bytes"), std::string::npos) << cause;
  // The last row needs its own bytes only, not a whole pitch: a padded pitch
  // with a buffer cut after the last row's pixels still fits.
  EXPECT_EQ(dmabufImportObstacle(kYuyv, {{0, 1344, 1280, 480, 1344u * 479u + 1280u}}, std::nullopt), "");
}

TEST(DmabufImportCheck, APitchShorterThanARowIsTheCause) {
  const std::string cause = dmabufImportObstacle(kYuyv, {{0, 1000, 1280, 480, std::nullopt}}, std::nullopt);
  EXPECT_EQ(cause, "plane layout: plane 0's pitch 1000 bytes is shorter than its row of 1280");
}

TEST(DmabufImportCheck, TheDriversRefusalIsNamedByItsError) {
  EXPECT_NE(eglImportRefusalCause(0x3009).find("EGL_BAD_MATCH"), std::string::npos);
  EXPECT_NE(eglImportRefusalCause(0x300C).find("not a dmabuf"), std::string::npos);
  EXPECT_NE(eglImportRefusalCause(0x3002).find("EGL_BAD_ACCESS"), std::string::npos);
  EXPECT_EQ(eglImportRefusalCause(0x3010), "the driver refused the import (EGL error 0x3010)");
}

TEST(DmabufImportCheck, EachPlanesSizeAndCpuMappingFollowTheRefusal) {
  DmabufPlaneLayout mapped{0, 1908, 1908, 480, 917504};
  mapped.cpu_mapping_errno = 0;
  DmabufPlaneLayout refused = mapped;
  refused.cpu_mapping_errno = EINVAL;
  DmabufPlaneLayout unknown{0, 1908, 1908, 480, std::nullopt};
  unknown.buffer_size_errno = ESPIPE;
  const std::string bad_alloc = eglImportRefusalCause(0x3003);
  EXPECT_EQ(eglImportRefusalCause(0x3003, {mapped}), bad_alloc + "; plane 0's dmabuf: 917504 bytes, the CPU maps it");
  EXPECT_EQ(eglImportRefusalCause(0x3003, {mapped, refused}),
            bad_alloc + "; plane 0's dmabuf: 917504 bytes, the CPU maps it; plane 1's dmabuf: 917504 bytes, the CPU "
                        "cannot map it as a software renderer would (mmap: " + std::strerror(EINVAL) + ")");
  // Not mapped (a refusal before the driver was asked): the size alone.
  EXPECT_EQ(eglImportRefusalCause(0x3003, {unknown}),
            bad_alloc + "; plane 0's dmabuf: size unknown (lseek: " + std::strerror(ESPIPE) + ")");
  DmabufPlaneLayout empty{0, 1908, 1908, 480, std::nullopt};
  EXPECT_EQ(eglImportRefusalCause(0x3003, {empty}), bad_alloc + "; plane 0's dmabuf: size unknown (lseek says 0 bytes)");
}

}  // namespace
}  // namespace probelight::passes
