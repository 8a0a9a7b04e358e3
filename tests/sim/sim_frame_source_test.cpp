// SimFrameSource on the ThreadedFrameSource seam.
#include <gtest/gtest.h>

#include <chrono>
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

}  // namespace
}  // namespace probelight
