// passes::chooseEdgeAntialiasing: which way the model's edges are smoothed
// for a GPU's capabilities, a framebuffer and a requested sample count. Pure:
// no context needed.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "gles/capabilities.hpp"
#include "gles_test_support.hpp"
#include "ibl/camera_projection.hpp"
#include "passes/edge_antialiasing.hpp"

namespace probelight {
namespace {

using passes::EdgeStrategy;

// A core GLES2 GPU with room for a 4x layer of a 1080p frame (a Pi 4's V3D
// reports 4096 for all three limits).
gles::Capabilities coreGles2() {
  gles::Capabilities caps;
  caps.max_texture_size_px = 4096;
  caps.max_renderbuffer_size_px = 4096;
  caps.max_viewport_px = 4096;
  return caps;
}

gles::Capabilities withRenderToTextureMsaa(int max_samples) {
  gles::Capabilities caps = coreGles2();
  caps.multisampled_render_to_texture = true;
  caps.max_samples = max_samples;
  return caps;
}

TEST(EdgeAntialiasing, OneSampleOrFewerIsOff) {
  for (int requested : {1, 0, -3}) {
    const auto choice = passes::chooseEdgeAntialiasing(withRenderToTextureMsaa(4), requested, 4, 640, 480);
    EXPECT_EQ(choice.strategy, EdgeStrategy::kOff) << requested;
    EXPECT_EQ(choice.samples, 1);
    EXPECT_FALSE(choice.usesLayer());
  }
}

TEST(EdgeAntialiasing, AMultisampledTargetIsUsedAsItIs) {
  // Even with the EXT on offer: the target resolves itself, a layer would only add a pass.
  const auto choice = passes::chooseEdgeAntialiasing(withRenderToTextureMsaa(8), 4, 4, 640, 480);
  EXPECT_EQ(choice.strategy, EdgeStrategy::kMultisampleConfig);
  EXPECT_EQ(choice.samples, 4);
  EXPECT_FALSE(choice.usesLayer());
  // GL_SAMPLES 1 is a single-sampled target, as 0 is.
  EXPECT_NE(passes::chooseEdgeAntialiasing(coreGles2(), 4, 1, 640, 480).strategy, EdgeStrategy::kMultisampleConfig);
}

TEST(EdgeAntialiasing, TheExtensionGivesMsaaUpToItsMaximum) {
  auto choice = passes::chooseEdgeAntialiasing(withRenderToTextureMsaa(4), 4, 0, 1920, 1080);
  EXPECT_EQ(choice.strategy, EdgeStrategy::kMultisampleRenderToTexture);
  EXPECT_EQ(choice.samples, 4);
  EXPECT_EQ(choice.grid, 1);
  EXPECT_TRUE(choice.usesLayer());
  choice = passes::chooseEdgeAntialiasing(withRenderToTextureMsaa(4), 16, 0, 1920, 1080);
  EXPECT_EQ(choice.samples, 4);
  choice = passes::chooseEdgeAntialiasing(withRenderToTextureMsaa(8), 2, 0, 1920, 1080);
  EXPECT_EQ(choice.samples, 2);
  // An EXT that reports fewer than 2 samples offers no MSAA: the core path.
  choice = passes::chooseEdgeAntialiasing(withRenderToTextureMsaa(1), 4, 0, 640, 480);
  EXPECT_EQ(choice.strategy, EdgeStrategy::kOrderedGridSupersampling);
}

TEST(EdgeAntialiasing, CoreGles2GetsTheSmallestEvenGridWithTheSamplesAsked) {
  struct Case {
    int requested, grid;
  } cases[] = {{2, 2}, {4, 2}, {5, 4}, {8, 4}, {16, 4}, {64, 4}};
  for (const Case& c : cases) {
    const auto choice = passes::chooseEdgeAntialiasing(coreGles2(), c.requested, 0, 640, 480);
    EXPECT_EQ(choice.strategy, EdgeStrategy::kOrderedGridSupersampling) << c.requested;
    EXPECT_EQ(choice.grid, c.grid) << c.requested;
    EXPECT_EQ(choice.samples, c.grid * c.grid) << c.requested;
    EXPECT_EQ(choice.requested_samples, c.requested);
    EXPECT_TRUE(choice.usesLayer());
  }
}

TEST(EdgeAntialiasing, TheGridShrinksToFitTheSmallestLimit) {
  // 1920 x 4 = 7680 exceeds 4096; x 2 = 3840 fits.
  auto choice = passes::chooseEdgeAntialiasing(coreGles2(), 16, 0, 1920, 1080);
  EXPECT_EQ(choice.grid, 2);
  // Each of the three limits binds on its own.
  for (int which = 0; which < 3; ++which) {
    gles::Capabilities caps = coreGles2();
    (which == 0 ? caps.max_texture_size_px : which == 1 ? caps.max_renderbuffer_size_px : caps.max_viewport_px) = 2048;
    choice = passes::chooseEdgeAntialiasing(caps, 4, 0, 1280, 720);  // 2560 > 2048
    EXPECT_EQ(choice.strategy, EdgeStrategy::kOff) << which;
    EXPECT_NE(choice.reason.find("2048"), std::string::npos) << choice.reason;
    choice = passes::chooseEdgeAntialiasing(caps, 16, 0, 1024, 600);  // 4096 > 2048, 2048 fits
    EXPECT_EQ(choice.grid, 2) << which;
  }
  // Height binds too.
  gles::Capabilities caps = coreGles2();
  caps.max_viewport_px = 1000;
  EXPECT_EQ(passes::chooseEdgeAntialiasing(caps, 4, 0, 400, 600).strategy, EdgeStrategy::kOff);
}

TEST(EdgeAntialiasing, MaskedCapabilitiesHaveNoRenderToTextureMsaa) {
  const gles::Capabilities plain = withRenderToTextureMsaa(4).withoutExtensions();
  EXPECT_FALSE(plain.multisampled_render_to_texture);
  EXPECT_EQ(plain.max_samples, 0);
  EXPECT_EQ(plain.renderbuffer_storage_multisample, nullptr);
  EXPECT_EQ(plain.max_renderbuffer_size_px, 4096);
  EXPECT_EQ(passes::chooseEdgeAntialiasing(plain, 4, 0, 640, 480).strategy, EdgeStrategy::kOrderedGridSupersampling);
}

TEST(EdgeAntialiasing, StrategiesHaveTheReportsNames) {
  EXPECT_STREQ(passes::edgeStrategyName(EdgeStrategy::kOff), "off");
  EXPECT_STREQ(passes::edgeStrategyName(EdgeStrategy::kMultisampleConfig), "multisample_config");
  EXPECT_STREQ(passes::edgeStrategyName(EdgeStrategy::kMultisampleRenderToTexture), "multisample_render_to_texture");
  EXPECT_STREQ(passes::edgeStrategyName(EdgeStrategy::kOrderedGridSupersampling), "ordered_grid_supersampling");
}

// projectedBounds against the projection itself: every point of random
// boxes (a 9^3 lattice through each, corners and insides) projects into the
// rectangle, and the rectangle is not much larger than the points' own.
TEST(EdgeAntialiasing, ProjectedBoundsHoldEveryPointOfTheBox) {
  const CameraIntrinsics camera = test::testCamera();  // strong distortion
  std::mt19937 random(16);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int cut = 0;
  // Drawn one statement at a time: the order a constructor's arguments are
  // evaluated in differs between compilers, and so would the boxes.
  auto draw = [&] {
    glm::dvec3 v;
    for (int axis = 0; axis < 3; ++axis) v[axis] = unit(random);
    return v;
  };
  for (int trial = 0; trial < 200; ++trial) {
    const glm::dvec3 eye = glm::dvec3(-0.2, -0.15, 0.05) + glm::dvec3(0.4, -0.3, 0.3) * draw();
    const PoseCamFromWorld pose = test::lookAt(eye, {0.0, 0.0, 0.03});
    const glm::dvec3 centre = glm::dvec3(-0.1, -0.1, 0.0) + glm::dvec3(0.2, 0.2, 0.05) * draw();
    const glm::dvec3 half = glm::dvec3(0.005) + 0.06 * draw();
    const passes::PixelRect rect = passes::projectedBounds(camera, pose, centre - half, centre + half, 0.01, 0);
    const bool whole = rect == passes::PixelRect{0, 0, camera.width_px, camera.height_px};
    int inside_frame = 0;
    double low_x = 1e9, high_x = -1e9;
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; j <= 8; ++j)
        for (int k = 0; k <= 8; ++k) {
          const glm::dvec3 w = centre + half * (glm::dvec3(i, j, k) / 4.0 - 1.0);
          const glm::dvec2 pixel = ibl::projectToPixel(camera, pose.R_cam_from_world * w + pose.t_cam_from_world);
          const double column = std::floor(pixel.x + 0.5), row = std::floor(pixel.y + 0.5);
          if (column < 0 || row < 0 || column >= camera.width_px || row >= camera.height_px) continue;
          ++inside_frame;
          low_x = std::min(low_x, column);
          high_x = std::max(high_x, column);
          ASSERT_GE(column, rect.x) << trial;
          ASSERT_LT(column, rect.x + rect.width) << trial;
          ASSERT_GE(row, rect.y) << trial;
          ASSERT_LT(row, rect.y + rect.height) << trial;
        }
    if (inside_frame > 0 && !whole) {
      ++cut;
      // Tight: the lattice's own extent, plus a pixel of rounding, plus what
      // the distortion bows the bounding rectangle's corners out beyond the
      // box's own image (a few pixels at this lens's strength). Only for a
      // box wholly in the frame: of one that leaves it, the sparse lattice
      // misses the part between its last point inside and the frame's edge.
      if (inside_frame == 9 * 9 * 9) {
        EXPECT_LE(rect.width, 1.05 * (high_x - low_x + 1) + 4) << trial;
      }
    }
  }
  EXPECT_GT(cut, 150) << "the bounds must cut the layer, not give the whole frame";
}

TEST(EdgeAntialiasing, ProjectedBoundsOfBoxesBehindOrOffTheFrame) {
  const CameraIntrinsics camera = test::testCamera();
  const PoseCamFromWorld pose = test::lookAt({0.0, -0.3, 0.1}, {0.0, 0.0, 0.03});
  const passes::PixelRect whole{0, 0, camera.width_px, camera.height_px};
  // Straddling the camera (a corner behind it): the whole frame.
  EXPECT_EQ(passes::projectedBounds(camera, pose, {-0.05, -0.35, 0.05}, {0.05, -0.25, 0.15}, 0.01, 2), whole);
  // Well to the side, in front: nothing.
  EXPECT_TRUE(passes::projectedBounds(camera, pose, {0.24, 0.0, 0.08}, {0.27, 0.03, 0.1}, 0.01, 2).empty());
  // Far out to the side (past the distortion's range): the whole frame, not a guess.
  EXPECT_EQ(passes::projectedBounds(camera, pose, {3.0, -0.29, 0.0}, {3.1, -0.28, 0.1}, 0.01, 2), whole);
}

}  // namespace
}  // namespace probelight
