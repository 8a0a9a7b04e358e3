#include "app/heap_release.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "binary_test_support.hpp"


namespace probelight {
namespace {

TEST(HeapReleasePolicy, ReleasesOncePerRiseOfTheEventCount) {
  HeapReleasePolicy policy;
  EXPECT_FALSE(policy.releaseAfter(0)) << "no event yet";
  EXPECT_TRUE(policy.releaseAfter(1));
  EXPECT_FALSE(policy.releaseAfter(1)) << "the frames after the event";
  EXPECT_TRUE(policy.releaseAfter(3)) << "two events in one frame: one release";
  EXPECT_FALSE(policy.releaseAfter(3));
  EXPECT_FALSE(policy.releaseAfter(2)) << "a count never falls; if it did, nothing new happened";
}

long long residentKib() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stoll(line.substr(6));
  return -1;
}

// What the soak saw, made on purpose: 32 MiB of small blocks (each below
// the mmap threshold, so from the heap), touched, then freed, all but the
// last one, which pins the top of the heap so that free() cannot shrink it.
// The 32 MiB stay resident until the release hands the free pages back.
TEST(HeapRelease, GivesFreedHeapPagesBackToTheSystem) {
#if defined(PROBELIGHT_TEST_UNDER_ASAN) || !defined(__GLIBC__)
  GTEST_SKIP() << "the sanitizer's allocator (or a libc other than glibc) is not the one released";
#else
  constexpr std::size_t kBlockBytes = 2048, kBlocks = 16384;  // 32 MiB
  std::vector<char*> blocks(kBlocks);
  for (char*& block : blocks) {
    block = static_cast<char*>(std::malloc(kBlockBytes));
    ASSERT_NE(block, nullptr);
    std::memset(block, 0x5a, kBlockBytes);
  }
  const long long filled_kib = residentKib();
  for (std::size_t i = 0; i + 1 < kBlocks; ++i) std::free(blocks[i]);
  const long long freed_kib = residentKib();
  ASSERT_GT(filled_kib, 0);
  // free() gave (almost) nothing back: the pages are between the heap's
  // start and its pinned top. A tenth of the blocks is the margin for what
  // the test framework allocates and frees meanwhile.
  EXPECT_GT(freed_kib, filled_kib - 32 * 1024 / 10) << "free() already returned the pages";
  EXPECT_TRUE(releaseFreeHeapToSystem());
  const long long released_kib = residentKib();
  // Every whole free page goes back: all of the 32 MiB but the chunk
  // headers at page edges and the pinned block; three quarters is the bound
  // that leaves the margin above.
  EXPECT_LT(released_kib, freed_kib - 3 * 32 * 1024 / 4) << "from " << freed_kib << " KiB to " << released_kib;
  std::free(blocks.back());
#endif
}

}  // namespace
}  // namespace probelight
