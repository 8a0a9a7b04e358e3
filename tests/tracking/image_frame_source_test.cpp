// ImageFrameSource: files in name order, undecodable ones skipped, end of stream.
#include <filesystem>
#include <memory>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "capture/image_frame_source.hpp"
#include "capture/scheduled_camera_loss.hpp"
#include "test_support.hpp"

namespace probelight {
namespace {

using namespace std::chrono_literals;
using testing::TempFolder;

// Writes a solid-colour PNG; `rgb` is the colour the frame must carry.
void writeSolidPng(const std::string& path, int width, int height, cv::Vec3b rgb) {
  cv::Mat bgr(height, width, CV_8UC3, cv::Scalar(rgb[2], rgb[1], rgb[0]));
  ASSERT_TRUE(cv::imwrite(path, bgr));
}

struct ReceivedFrame {
  std::string origin;
  std::uint64_t sequence;
  int width, height;
  cv::Vec3b first_pixel_rgb;
};

// Collects up to `limit` frames; returns how the stream ended.
FrameWait collect(FrameSource& source, std::vector<ReceivedFrame>& frames, std::size_t limit = 100) {
  for (;;) {
    FrameLease lease;
    FrameWait wait = source.waitFrame(2000ms, lease);
    if (wait != FrameWait::kFrame) return wait;
    const ImageRGB8& rgb = lease->rgb;
    frames.push_back({lease->metadata.origin, lease->metadata.sequence, rgb.width, rgb.height,
                      cv::Vec3b(rgb.pixels[0], rgb.pixels[1], rgb.pixels[2])});
    if (frames.size() >= limit) return FrameWait::kFrame;
  }
}

TEST(ImageFrameSource, DeliversFilesInNameOrderSkippingUndecodableOnes) {
  TempFolder folder;
  writeSolidPng(folder.file("frame_2.png"), 40, 30, {0, 0, 255});
  writeSolidPng(folder.file("frame_0.png"), 20, 10, {255, 0, 0});
  writeSolidPng(folder.file("frame_1.png"), 30, 20, {0, 255, 0});
  folder.write("frame_1x_corrupt.png", "this is not a PNG");
  folder.write("notes.txt", "not an image, and not named like one: ignored in folder mode");

  ImageFrameSource source(folder.path().string());
  std::string error;
  ::testing::internal::CaptureStderr();  // before the producer thread starts
  ASSERT_TRUE(source.start(error)) << error;
  EXPECT_EQ(source.files().size(), 4u);  // the .txt is not listed
  std::vector<ReceivedFrame> frames;
  FrameWait end = collect(source, frames);
  std::string warnings = ::testing::internal::GetCapturedStderr();

  EXPECT_EQ(end, FrameWait::kEndOfStream);
  EXPECT_TRUE(source.lastError().empty()) << source.lastError();
  ASSERT_EQ(frames.size(), 3u);
  const std::string names[] = {"frame_0.png", "frame_1.png", "frame_2.png"};
  const cv::Vec3b colours[] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};  // RGB, so channel order is checked
  const int widths[] = {20, 30, 40};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(frames[i].origin, folder.file(names[i]));
    EXPECT_EQ(frames[i].sequence, i);
    EXPECT_EQ(frames[i].width, widths[i]);
    EXPECT_EQ(frames[i].first_pixel_rgb, colours[i]) << names[i];  // PNG is lossless: exact
  }
  // One warning line naming the broken file.
  EXPECT_NE(warnings.find("frame_1x_corrupt.png"), std::string::npos) << warnings;
  EXPECT_EQ(std::count(warnings.begin(), warnings.end(), '\n'), 1) << warnings;
}

// Exposure sets: ev<stops> subfolders make the replay a camera with exposure
// control. A ladder asked while frame 0 is held reaches frame 3 on (the pool
// of 3 has frames 1 and 2 made), each frame from the set nearest its
// exposure, and the metadata says the exposure it got.
TEST(ImageFrameSource, ExposureSetsServeALadderFromTheNearestSet) {
  TempFolder folder;
  std::filesystem::create_directories(folder.path() / "ev-2");
  std::filesystem::create_directories(folder.path() / "ev-4");
  std::filesystem::create_directories(folder.path() / "evening");  // not a set: ignored
  for (int i = 0; i < 8; ++i) {
    const std::string name = "f_" + std::to_string(i) + ".png";
    writeSolidPng(folder.file(name), 8, 8, {200, 200, 200});
    writeSolidPng((folder.path() / "ev-2" / name).string(), 8, 8, {50, 50, 50});
    writeSolidPng((folder.path() / "ev-4" / name).string(), 8, 8, {12, 12, 12});
  }
  ImageFrameSource source(folder.path().string(), /*loop=*/false, /*pool_size=*/3);
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  ASSERT_EQ(source.exposureSets().size(), 2u);
  EXPECT_EQ(source.exposureSets()[0].first, -4.0);
  EXPECT_TRUE(source.lockExposure(true));
  std::vector<std::pair<int, double>> got;  // (first pixel, exposure_us) per frame
  for (int i = 0; i < 8; ++i) {
    FrameLease lease;
    ASSERT_EQ(source.waitFrame(2000ms, lease), FrameWait::kFrame);
    got.emplace_back(lease->rgb.pixels[0], lease->metadata.exposure_us);
    // 2400 us is 2.06 stops under 10 ms (nearest set: ev-2), 700 us 3.8 (ev-4).
    if (i == 0) {
      ASSERT_TRUE(source.setExposureLadder({{2400.0, 1.0}, {700.0, 1.0}}));
    }
  }
  const double base = ImageFrameSource::kReplayExposureUs;
  const std::vector<std::pair<int, double>> want = {{200, base},       {200, base},       {200, base},
                                                    {50, base / 4.0},  {12, base / 16.0}, {12, base / 16.0},
                                                    {12, base / 16.0}, {12, base / 16.0}};
  EXPECT_EQ(got, want);
}

TEST(ImageFrameSource, WithoutExposureSetsThereIsNoExposureControl) {
  TempFolder folder;
  writeSolidPng(folder.file("a.png"), 8, 8, {1, 2, 3});
  ImageFrameSource source(folder.path().string());
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  EXPECT_FALSE(source.lockExposure(true));
  EXPECT_FALSE(source.setExposureLadder({{1000.0, 1.0}}));
  FrameLease lease;
  ASSERT_EQ(source.waitFrame(2000ms, lease), FrameWait::kFrame);
  EXPECT_EQ(lease->metadata.exposure_us, 0.0);  // unknown
}

TEST(ImageFrameSource, GlobPatternAndLooping) {
  TempFolder folder;
  writeSolidPng(folder.file("b.png"), 8, 8, {0, 0, 0});
  writeSolidPng(folder.file("a.png"), 8, 8, {0, 0, 0});
  writeSolidPng(folder.file("c.jpg"), 8, 8, {0, 0, 0});
  ImageFrameSource source((folder.path() / "*.png").string(), /*loop=*/true);
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  std::vector<ReceivedFrame> frames;
  collect(source, frames, 5);
  ASSERT_EQ(frames.size(), 5u);
  const char* expected[] = {"a.png", "b.png", "a.png", "b.png", "a.png"};
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(frames[i].origin, folder.file(expected[i])) << i;
    EXPECT_EQ(frames[i].sequence, i);
  }
  source.stop();
}

// The injected loss (faults.camera_loss_*), around a real source: after
// every 2 frames the next wait fails as a lost camera's does, until a stop
// and the second start() (the first fails as told); then frames come again,
// from the replay's start, as a restarted camera's do.
TEST(ScheduledCameraLoss, LosesTheCameraOnScheduleAndFailsTheToldRestarts) {
  TempFolder folder;
  for (const char* name : {"a.png", "b.png", "c.png"}) writeSolidPng(folder.file(name), 8, 8, {0, 0, 0});
  ScheduledCameraLoss source(std::make_unique<ImageFrameSource>(folder.path().string()), 2, 1);
  EXPECT_EQ(source.name(), "images:" + folder.path().string());
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  for (int cycle = 0; cycle < 2; ++cycle) {
    std::vector<ReceivedFrame> frames;
    EXPECT_EQ(collect(source, frames), FrameWait::kError) << "cycle " << cycle;
    ASSERT_EQ(frames.size(), 2u) << "cycle " << cycle;
    EXPECT_EQ(frames[0].origin, folder.file("a.png")) << "the replay starts over";
    EXPECT_EQ(frames[1].origin, folder.file("b.png"));
    EXPECT_NE(source.lastError().find("faults.camera_loss_every_frames"), std::string::npos) << source.lastError();
    EXPECT_EQ(source.lossesInjected(), static_cast<std::uint64_t>(cycle + 1));
    source.stop();
    EXPECT_FALSE(source.start(error));
    EXPECT_NE(error.find("faults.camera_loss_failed_restarts"), std::string::npos) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
    error.clear();
    ASSERT_TRUE(source.start(error)) << error;
  }
  source.stop();
}

TEST(ImageFrameSource, NothingToReadFailsAtStartWithOneLine) {
  TempFolder folder;
  std::string pattern = (folder.path() / "*.png").string();
  ImageFrameSource by_pattern(pattern);
  std::string error;
  EXPECT_FALSE(by_pattern.start(error));
  EXPECT_NE(error.find(pattern), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;

  ImageFrameSource by_folder(folder.path().string());
  error.clear();
  EXPECT_FALSE(by_folder.start(error));
  EXPECT_NE(error.find(folder.path().string()), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
}

TEST(ImageFrameSource, AllFilesBrokenWhileLoopingIsAnErrorNotAHang) {
  TempFolder folder;
  folder.write("a.png", "broken");
  folder.write("b.png", "broken too");
  ImageFrameSource source(folder.path().string(), /*loop=*/true);
  std::string error;
  ::testing::internal::CaptureStderr();  // before the producer thread starts
  ASSERT_TRUE(source.start(error)) << error;
  std::vector<ReceivedFrame> frames;
  FrameWait end = collect(source, frames);
  ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(end, FrameWait::kError);
  EXPECT_TRUE(frames.empty());
  EXPECT_NE(source.lastError().find("could be decoded"), std::string::npos) << source.lastError();
}

TEST(ImageFrameSource, DestroyingARunningSourceStopsItsThread) {
  TempFolder folder;
  writeSolidPng(folder.file("a.png"), 8, 8, {1, 2, 3});
  std::string error;
  {
    ImageFrameSource source(folder.path().string(), /*loop=*/true, /*pool_size=*/2);
    ASSERT_TRUE(source.start(error)) << error;
    FrameLease lease;
    ASSERT_EQ(source.waitFrame(2000ms, lease), FrameWait::kFrame);
    // The producer now blocks on a full pool; leaving scope must stop and join it.
  }
  SUCCEED();  // reaching here without a hang or crash is the assertion
}

}  // namespace
}  // namespace probelight
