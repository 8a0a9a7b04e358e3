// SimFrameSource on the ThreadedFrameSource seam.
#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "capture/sim_frame_source.hpp"
#include "sim_test_helpers.hpp"

namespace probelight {
namespace {

using namespace std::chrono_literals;

std::shared_ptr<const sim::World> smallWorld() {
  sim::SceneConfig scene = sim::testing::smallScene();
  scene.supersample_per_axis = 1;
  return std::make_shared<const sim::World>(scene);
}

TEST(SimFrameSource, DeliversFramesInOrderWithTruthThenEndOfStream) {
  auto world = smallWorld();
  SimFrameSource source(world, 5);
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  for (std::uint64_t i = 0; i < 5; ++i) {
    FrameLease lease;
    ASSERT_EQ(source.waitFrame(5s, lease), FrameWait::kFrame) << i;
    EXPECT_EQ(lease->metadata.sequence, i);
    EXPECT_EQ(lease->metadata.timestamp_ns, static_cast<std::int64_t>(i * 1'000'000'000ull / 30));
    EXPECT_EQ(lease->metadata.origin, "sim:" + std::to_string(i));
    ASSERT_TRUE(lease->metadata.truth.has_value());
    FrameTruth expected = world->truth(i);
    EXPECT_EQ(lease->metadata.truth->probe_center_px, expected.probe_center_px);
    EXPECT_EQ(lease->metadata.truth->pose.t_cam_from_world, expected.pose.t_cam_from_world);
    ImageRGB8 direct;
    FrameTruth ignored;
    world->render(i, direct, ignored);
    EXPECT_EQ(lease->rgb.pixels, direct.pixels) << i;
  }
  FrameLease lease;
  EXPECT_EQ(source.waitFrame(5s, lease), FrameWait::kEndOfStream);
  EXPECT_TRUE(source.lastError().empty());
}

TEST(SimFrameSource, ProducerWaitsForLeasesToComeBackToThePool) {
  SimFrameSource source(smallWorld(), 0, 3);
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  std::vector<FrameLease> held(3);
  for (auto& lease : held) ASSERT_EQ(source.waitFrame(5s, lease), FrameWait::kFrame);
  // All three buffers are lent out: nothing more can be made.
  FrameLease extra;
  EXPECT_EQ(source.waitFrame(300ms, extra), FrameWait::kTimeout);
  held[0].release();
  ASSERT_EQ(source.waitFrame(5s, extra), FrameWait::kFrame);
  EXPECT_EQ(extra->metadata.sequence, 3u);
  // Dropping leases one at a time keeps an endless stream flowing.
  held.clear();
  extra.release();
  for (std::uint64_t i = 4; i < 12; ++i) {
    FrameLease lease;
    ASSERT_EQ(source.waitFrame(5s, lease), FrameWait::kFrame);
    EXPECT_EQ(lease->metadata.sequence, i);
  }
  source.stop();
}

// An exposure ladder, as a bracket asks for it: it starts a pool's length
// after the frame the consumer holds (the frames made ahead keep their
// exposure, as a camera's queued requests do), one rung a frame, the last
// held; ending it early drops the rungs not begun, from a pool's length
// after the frame held then. The sensor's shortest exposure clamps a rung,
// and the metadata says what each frame got; the pixels follow it.
TEST(SimFrameSource, AnExposureLadderArrivesOneRungAFrameAfterThePoolsLatency) {
  SimCameraOptions options;
  options.min_exposure_us = 100.0;
  auto world = smallWorld();
  SimFrameSource source(world, 0, 3, options);
  ASSERT_EQ(source.shortestExposureUs(), 100.0);
  std::string error;
  ASSERT_TRUE(source.start(error)) << error;
  auto next = [&]() {
    FrameLease lease;
    EXPECT_EQ(source.waitFrame(5s, lease), FrameWait::kFrame);
    return lease;
  };
  FrameLease held = next();  // frame 0
  ASSERT_EQ(held->metadata.sequence, 0u);
  ASSERT_TRUE(source.setExposureLadder({{1250.0, 1.0}, {156.25, 1.0}, {19.5, 1.0}}));
  held.release();
  std::vector<double> exposures_us;
  for (int i = 1; i <= 7; ++i) {
    FrameLease lease = next();
    ASSERT_EQ(lease->metadata.sequence, static_cast<std::uint64_t>(i));
    exposures_us.push_back(lease->metadata.exposure_us);
    if (i == 4) {
      // The pixels are the world's at that exposure: EV -6 here.
      ImageRGB8 direct;
      FrameTruth ignored;
      world->render(4, direct, ignored, std::log2(156.25 / 10000.0));
      EXPECT_EQ(lease->rgb.pixels, direct.pixels);
      // Ended here: frames 5 and 6 were asked for already, 7 on are back.
      ASSERT_TRUE(source.setExposureLadder({}));
    }
  }
  const std::vector<double> expected_us = {10000.0, 10000.0, 1250.0, 156.25, 100.0, 100.0, 10000.0};
  EXPECT_EQ(exposures_us, expected_us);
  options.min_exposure_reported = false;
  EXPECT_FALSE(SimFrameSource(world, 1, 3, options).shortestExposureUs().has_value());
  source.stop();
}

// The simulated lens (issue 48), as the libcamera source drives a Camera
// Module 3's: held at camera.yaml's position and saying so in every frame;
// left to its own focus when the file names none; and a camera without a
// lens runs on with one warning.
std::vector<std::optional<double>> lensPositionsOf(SimFrameSource& source, int frames) {
  std::vector<std::optional<double>> positions;
  std::string error;
  EXPECT_TRUE(source.start(error)) << error;
  for (int i = 0; i < frames; ++i) {
    FrameLease lease;
    EXPECT_EQ(source.waitFrame(5s, lease), FrameWait::kFrame) << i;
    if (lease) positions.push_back(lease->metadata.lens_position_dioptres);
  }
  return positions;
}

TEST(SimFrameSource, ALensIsHeldAtCameraYamlsPositionAndEveryFrameSaysSo) {
  const auto world = smallWorld();
  SimCameraOptions options;
  options.lens_control = true;
  options.lens_position_dioptres = 3.25;
  SimFrameSource held(world, 3, 3, options);
  EXPECT_EQ(lensPositionsOf(held, 3), (std::vector<std::optional<double>>(3, 3.25)));
  EXPECT_EQ(held.focusWarning(), "");

  // No position asked: no focus control, the lens stays where its own
  // autofocus keeps it.
  options.lens_position_dioptres.reset();
  SimFrameSource own(world, 2, 3, options);
  EXPECT_EQ(lensPositionsOf(own, 2), (std::vector<std::optional<double>>(2, options.lens_own_position_dioptres)));
  EXPECT_NE(options.lens_own_position_dioptres, 3.25) << "the two cases must differ for this test to mean anything";
  EXPECT_EQ(own.focusWarning(), "");
}

TEST(SimFrameSource, ACameraWithoutALensRunsOnWithOneWarning) {
  SimCameraOptions options;
  options.lens_position_dioptres = 3.25;
  SimFrameSource fixed_focus(smallWorld(), 2, 3, options);
  EXPECT_EQ(lensPositionsOf(fixed_focus, 2), (std::vector<std::optional<double>>(2, std::nullopt)));
  const std::string warning = fixed_focus.focusWarning();
  EXPECT_NE(warning.find("has no lens control (LensPosition)"), std::string::npos) << warning;
  EXPECT_NE(warning.find("lens_position_dioptres 3.25"), std::string::npos) << warning;
  EXPECT_EQ(warning.find('\n'), std::string::npos) << warning;
}

}  // namespace
}  // namespace probelight
