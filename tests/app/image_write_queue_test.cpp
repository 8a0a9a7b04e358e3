// ImageWriteQueue: frames are written off the caller's thread, in order,
// with a bounded queue, and a failed write is reported, not lost.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "capture/rgb_image_io.hpp"
#include "display/image_write_queue.hpp"

namespace probelight {
namespace {

ImageRGB8 imageOfValue(std::uint8_t value) {
  ImageRGB8 image;
  image.resize(4, 3);
  std::fill(image.pixels.begin(), image.pixels.end(), value);
  return image;
}

TEST(ImageWriteQueue, WritesEveryImageInOrderOffTheCallersThread) {
  std::mutex mutex;
  std::vector<std::string> written;
  std::vector<std::uint8_t> values;
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<bool> on_caller_thread{false};
  ImageWriteQueue queue([&](const std::string& path, const ImageRGB8& image, std::string&) {
    if (std::this_thread::get_id() == caller) on_caller_thread = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::lock_guard lock(mutex);
    written.push_back(path);
    values.push_back(image.pixels[0]);
    return true;
  });
  std::string error;
  for (int i = 0; i < 8; ++i) ASSERT_TRUE(queue.push("f" + std::to_string(i), imageOfValue(static_cast<std::uint8_t>(i)), error)) << error;
  ASSERT_TRUE(queue.finish(error)) << error;
  EXPECT_EQ(queue.written(), 8);
  EXPECT_FALSE(on_caller_thread);
  ASSERT_EQ(written.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(written[static_cast<size_t>(i)], "f" + std::to_string(i));
    EXPECT_EQ(values[static_cast<size_t>(i)], i);
  }
}

// push() waits while `depth` images are queued, so a slow disk holds up the
// caller instead of filling memory.
TEST(ImageWriteQueue, TheQueueIsBounded) {
  std::atomic<bool> release{false};
  std::atomic<int> started{0};
  ImageWriteQueue queue(
      [&](const std::string&, const ImageRGB8&, std::string&) {
        ++started;
        while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        return true;
      },
      2);
  std::string error;
  ASSERT_TRUE(queue.push("a", imageOfValue(1), error));  // taken by the worker
  while (started == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_TRUE(queue.push("b", imageOfValue(2), error));
  ASSERT_TRUE(queue.push("c", imageOfValue(3), error));  // the queue holds b and c: full
  std::atomic<bool> fourth_pushed{false};
  std::thread pusher([&] {
    std::string e;
    queue.push("d", imageOfValue(4), e);
    fourth_pushed = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(fourth_pushed) << "push() returned with the queue full";
  release = true;
  pusher.join();
  EXPECT_TRUE(fourth_pushed);
  ASSERT_TRUE(queue.finish(error)) << error;
  EXPECT_EQ(queue.written(), 4);
}

// A real PNG into a folder that is not there: the failure names the file,
// and is reported by the next push and by finish().
TEST(ImageWriteQueue, AFailedWriteIsReportedWithTheFileName) {
  const std::string bad = ::testing::TempDir() + "/no-such-folder-probelight/frame.png";
  ImageWriteQueue queue(
      [](const std::string& path, const ImageRGB8& image, std::string& why) { return writeRgbPng(path, image, why); });
  std::string error;
  ASSERT_TRUE(queue.push(bad, imageOfValue(7), error));
  EXPECT_FALSE(queue.finish(error));
  EXPECT_NE(error.find(bad), std::string::npos) << error;
  EXPECT_NE(error.find("No such file or directory"), std::string::npos) << error;  // and why
  std::string again;
  EXPECT_FALSE(queue.push(::testing::TempDir() + "/ok.png", imageOfValue(8), again));
  EXPECT_NE(again.find(bad), std::string::npos) << again;
  EXPECT_EQ(queue.written(), 0);
}

}  // namespace
}  // namespace probelight
