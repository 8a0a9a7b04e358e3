#include "ibl/probe_to_cube.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "ibl/color_transfer.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

// Smooth encoded (sRGB) environment: each channel in [0.1, 0.9].
glm::dvec3 encodedEnvironment(const glm::dvec3& w) { return {0.5 + 0.4 * w.z, 0.5 + 0.4 * w.x, 0.5 - 0.3 * w.y}; }

// Camera image of the ball alone: each pixel shows the environment in the
// direction its centre's ray reflects to (OpenCV convention: pixel (u, v) centred at integer (u, v)).
ImageRGB8 renderBall(const MirrorBallView& view, double reflectance) {
  ImageRGB8 image;
  image.resize(view.camera.width_px, view.camera.height_px);
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      const auto direction = pixelToReflectedDirection(view, {u, v});
      if (!direction) continue;
      const glm::dvec3 encoded = encodedEnvironment(*direction);
      for (int c = 0; c < 3; ++c) {
        const double seen = linearToSrgb(srgbToLinear(encoded[c]) * reflectance);
        image.row(v)[3 * u + c] = static_cast<std::uint8_t>(std::lround(255.0 * seen));
      }
    }
  }
  return image;
}

TEST(ProbeToCube, RecoversTheEnvironmentTheBallReflects) {
  const MirrorBallView view = testing::kioskBallView(0.40, {400.0, 200.0});
  const double reflectance = 0.7;
  const ImageRGB8 image = renderBall(view, reflectance);
  ProbeToCubeParams params;
  params.face_size = 16;
  params.probe_reflectance = reflectance;
  const CubeMapRGB cube = probeImageToCubeMap(view, image, params);
  const glm::dvec3 away_from_camera = glm::normalize(view.center_w - view.pose.cameraCenterWorld());
  double worst_encoded = 0.0;
  int blind = 0;
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < params.face_size; ++y) {
      for (int x = 0; x < params.face_size; ++x) {
        const glm::dvec3 w = cubeTexelCenterDirection(face, x, y, params.face_size);
        const glm::vec3 texel = cube.texel(face, x, y);
        if (!reflectedDirectionToPixel(view, w, params.normal_iterations)) {
          EXPECT_EQ(texel, glm::vec3(0.0f));  // the blind spot stays black
          ++blind;
          continue;
        }
        // Near the rim one pixel spans many degrees; judge the ball's inner part.
        if (testing::angleBetweenRad(w, away_from_camera) < glm::radians(60.0)) continue;
        for (int c = 0; c < 3; ++c) {
          // The texel is the room's radiance: the ball's dimming is divided out.
          const double recovered_encoded = linearToSrgb(texel[c]);
          worst_encoded = std::max(worst_encoded, std::abs(recovered_encoded - encodedEnvironment(w)[c]));
        }
      }
    }
  }
  std::cout << "[ probe ] worst encoded error " << worst_encoded * 255.0 << " /255, " << blind << " blind texels\n";
  // 0.5/255 rounding of the dimmed image, stretched ~(1/0.7)^(1/2.4) = 1.16x
  // when the dimming is divided out, plus bilinear reads of a field that
  // changes ~6/255 a pixel at 60 deg from the blind spot: its curvature adds
  // well under 1/255. A half-pixel slip in the pixel-centre convention costs
  // ~3/255 there, so 1.5/255 also pins that convention.
  EXPECT_LT(worst_encoded, 1.5 / 255.0);
}

TEST(ProbeToCube, EmptyImageGivesABlackCube) {
  const CubeMapRGB cube = probeImageToCubeMap(testing::kioskBallView(0.4, {320, 240}), ImageRGB8{}, {});
  EXPECT_EQ(cube.face_size, 64);
  EXPECT_EQ(cube.texel(3, 10, 10), glm::vec3(0.0f));
}

}  // namespace
}  // namespace probelight::ibl

namespace probelight::ibl {
namespace {

// A room whose radiance runs over four decades: a smooth sky (0.05-0.45)
// and a lamp (radiance 40) in a 12 deg cap, which an 8-bit frame clips.
glm::dvec3 brightRoom(const glm::dvec3& w) {
  const double sky = 0.25 + 0.2 * w.z;
  const glm::dvec3 lamp_direction = glm::normalize(glm::dvec3(0.2, -0.9, 0.4));  // toward the camera's side: well seen
  return glm::dvec3(glm::dot(w, lamp_direction) > std::cos(glm::radians(12.0)) ? 40.0 : sky);
}

// The ball at `ev` stops, as an 8-bit sRGB camera takes it.
ImageRGB8 exposeBall(const MirrorBallView& view, double ev) {
  ImageRGB8 image;
  image.resize(view.camera.width_px, view.camera.height_px);
  for (int v = 0; v < image.height; ++v)
    for (int u = 0; u < image.width; ++u) {
      const auto direction = pixelToReflectedDirection(view, {u, v});
      if (!direction) continue;
      const glm::dvec3 radiance = brightRoom(*direction) * std::exp2(ev);
      for (int c = 0; c < 3; ++c)
        image.row(v)[3 * u + c] = static_cast<std::uint8_t>(std::lround(255.0 * linearToSrgb(std::min(1.0, radiance[c]))));
    }
  return image;
}

// Frames taken from two places (the camera moved 6 px between the first
// and the others): merged through each frame's own view, every direction
// the ball shows well is the room's radiance within the codes' rounding,
// the lamp included; merged as if nothing had moved, the lamp's edges are
// wrong by a large factor.
TEST(ProbeToCube, ABracketFromAMovingCameraIsMergedThroughEachFramesPose) {
  const MirrorBallView first = testing::kioskBallView(0.40, {400.0, 200.0});
  const MirrorBallView moved = testing::kioskBallView(0.40, {406.0, 200.0});
  const std::vector<double> evs = {0.0, -3.0, -6.0, -9.0};
  std::vector<ImageRGB8> images;
  for (std::size_t i = 0; i < evs.size(); ++i) images.push_back(exposeBall(i == 0 ? first : moved, evs[i]));
  ProbeToCubeParams params;
  params.face_size = 32;
  params.samples_per_axis = 1;  // texel centres, compared with the room there
  auto merge = [&](bool registered) {
    std::vector<BracketView> frames;
    for (std::size_t i = 0; i < evs.size(); ++i)
      frames.push_back({&images[i], evs[i], (i == 0 || !registered) ? first : moved});
    std::vector<std::uint8_t> still_clipped;
    CubeMapRGB cube = bracketToCubeMap(frames, HdrMergeSettings{}, params, &still_clipped);
    long flagged = 0;
    for (const std::uint8_t flag : still_clipped) flagged += flag;
    EXPECT_EQ(flagged, 0) << "the lamp is measured at EV -6 and -9";
    return cube;
  };
  const CubeMapRGB registered = merge(true), unregistered = merge(false);
  const glm::dvec3 away_from_camera = glm::normalize(first.center_w - first.pose.cameraCenterWorld());
  double worst_registered = 0.0, worst_unregistered = 0.0;
  int lamp_texels = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < params.face_size; ++y)
      for (int x = 0; x < params.face_size; ++x) {
        const glm::dvec3 w = cubeTexelCenterDirection(face, x, y, params.face_size);
        // The ball's inner part in both views (near the rim a pixel spans
        // many degrees), and away from the lamp's edge by more than a
        // pixel's worth of direction there (~2 deg).
        if (testing::angleBetweenRad(w, away_from_camera) < glm::radians(60.0)) continue;
        const glm::dvec3 lamp_direction = glm::normalize(glm::dvec3(0.2, -0.9, 0.4));
        const double from_lamp_edge = std::abs(glm::degrees(testing::angleBetweenRad(w, lamp_direction)) - 12.0);
        if (from_lamp_edge < 3.0) continue;
        const double truth = brightRoom(w).g;
        lamp_texels += truth > 1.0 ? 1 : 0;
        worst_registered = std::max(worst_registered, std::abs(registered.texel(face, x, y).g / truth - 1.0));
        worst_unregistered = std::max(worst_unregistered, std::abs(unregistered.texel(face, x, y).g / truth - 1.0));
      }
  ASSERT_GT(lamp_texels, 5);
  std::cout << "[ probe ] bracket from a moving camera: worst relative error " << worst_registered << " registered, "
            << worst_unregistered << " not, over " << lamp_texels << " lamp texels and the sky\n";
  // Half a code of rounding in the frame that measured it: at most ~1.5%
  // for codes above 60 (sRGB's slope), and the merge takes the best
  // exposed; bilinear reads of a smooth sky add far less.
  EXPECT_LT(worst_registered, 0.03);
  EXPECT_GT(worst_unregistered, 0.5) << "6 px of motion must show when it is not undone";
}

}  // namespace
}  // namespace probelight::ibl

namespace probelight::ibl {
namespace {

// A camera that clips in one channel has its others wrong too: decoded from
// NV12, a clipped white lamp (Y' 255, chroma near neutral) comes out as
// (244, 255, 255): red below the clip. Counted as a measurement, that red
// (0.9 of the reference's white) would stand for a lamp of 40 in the merge
// and turn it cyan. A pixel with any channel clipped gives nothing in any
// channel: the lamp's red comes from the shorter frames, as its green does.
TEST(ProbeToCube, APixelClippedInOneChannelCountsInNone) {
  const MirrorBallView view = testing::kioskBallView(0.40, {400.0, 200.0});
  const std::vector<double> evs = {0.0, -3.0, -6.0, -9.0};
  std::vector<ImageRGB8> images;
  for (const double ev : evs) images.push_back(exposeBall(view, ev));
  int decoded_below_clip = 0;
  for (ImageRGB8* image : {&images[0], &images[1]})  // where the lamp clips
    for (std::size_t i = 0; i < image->pixels.size(); i += 3)
      if (image->pixels[i + 1] == 255) {
        image->pixels[i] = 244;
        ++decoded_below_clip;
      }
  ASSERT_GT(decoded_below_clip, 50);
  std::vector<BracketView> frames;
  for (std::size_t i = 0; i < evs.size(); ++i) frames.push_back({&images[i], evs[i], view});
  ProbeToCubeParams params;
  params.face_size = 32;
  params.samples_per_axis = 1;
  const CubeMapRGB cube = bracketToCubeMap(frames, HdrMergeSettings{}, params, nullptr);
  const glm::dvec3 lamp_direction = glm::normalize(glm::dvec3(0.2, -0.9, 0.4));
  double worst_red = 0.0;
  int lamp_texels = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < params.face_size; ++y)
      for (int x = 0; x < params.face_size; ++x) {
        const glm::dvec3 w = cubeTexelCenterDirection(face, x, y, params.face_size);
        if (glm::degrees(testing::angleBetweenRad(w, lamp_direction)) > 9.0) continue;  // inside the lamp
        ++lamp_texels;
        worst_red = std::max(worst_red, std::abs(cube.texel(face, x, y).r / 40.0 - 1.0));
      }
  ASSERT_GT(lamp_texels, 5);
  // As ABracketFromAMovingCameraIsMergedThroughEachFramesPose: half a code
  // of rounding in the frame that measured it.
  EXPECT_LT(worst_red, 0.03) << "the lamp's red is measured at EV -6 and -9, not read off 244";

  // The same for the image merge (hdr_bracket.hpp): a one-pixel bracket.
  ImageRGB8 long_frame, short_frame;
  long_frame.resize(1, 1);
  short_frame.resize(1, 1);
  long_frame.pixels = {244, 255, 255};
  short_frame.pixels = {137, 137, 137};  // 4.0 at EV -3: sRGB 0.5 of 1
  const HdrMergeResult merged = mergeBracket({{&long_frame, 0.0}, {&short_frame, -3.0}}, HdrMergeSettings{});
  const double expected = srgbToLinear(137 / 255.0) * 8.0;
  EXPECT_NEAR(merged.linear.at(0, 0).r, expected, 0.02 * expected);
  EXPECT_NEAR(merged.linear.at(0, 0).g, expected, 0.02 * expected);
}

}  // namespace
}  // namespace probelight::ibl
