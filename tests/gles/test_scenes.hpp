// Inputs that the GPU tests and mediump_test.cpp (the shaders' CPU twins at
// both precisions) share: the ball view and camera frame of the
// probe_to_cube tests, and the zenith-lamp room of the diffuse ones.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "gles_test_support.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"

namespace probelight::test {

inline constexpr double kProbeReflectance = 0.7;

inline ibl::MirrorBallView testBallView() {
  ibl::MirrorBallView view;
  view.camera = testCamera();
  view.center_w = {0.12, 0.0, 0.08};
  view.radius_m = 0.03;
  // Off-axis so the ball sits away from the image centre, where distortion
  // and perspective both matter.
  view.pose = lookAt({-0.10, -0.42, 0.36}, {0.02, 0.02, 0.02});
  return view;
}

// The camera frame of the ball in the analytic environment, rendered from
// exact per-pixel reflection (ibl::pixelToReflectedDirection); elsewhere a
// gradient so edge samples pick up something unlike the ball.
inline ImageRGB8 renderBallImage(const ibl::MirrorBallView& view) {
  ImageRGB8 image;
  image.resize(view.camera.width_px, view.camera.height_px);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      glm::dvec3 linear{0.05 + 0.4 * x / image.width, 0.3, 0.05 + 0.4 * y / image.height};
      if (auto reflected = ibl::pixelToReflectedDirection(view, {x, y})) {
        linear = analyticEnvironment(*reflected) * kProbeReflectance;
      }
      for (int c = 0; c < 3; ++c) {
        image.row(y)[3 * x + c] = static_cast<std::uint8_t>(std::lround(ibl::linearToSrgb(linear[c]) * 255.0));
      }
    }
  }
  return image;
}

// Max - min of the 2x2 bytes a bilinear sample at `pixel` reads (texcoord =
// (pixel + 0.5) / size: OpenCV pixel centres at integers), per channel, in 8-bit levels.
inline glm::dvec3 bilinearNeighbourhoodRange(const ImageRGB8& image, const glm::dvec2& pixel) {
  const int x0 = std::clamp(static_cast<int>(std::floor(pixel.x)), 0, image.width - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(pixel.y)), 0, image.height - 1);
  const int x1 = std::min(x0 + 1, image.width - 1);
  const int y1 = std::min(y0 + 1, image.height - 1);
  glm::dvec3 range(0.0);
  for (int c = 0; c < 3; ++c) {
    const int values[4] = {image.row(y0)[3 * x0 + c], image.row(y0)[3 * x1 + c], image.row(y1)[3 * x0 + c],
                           image.row(y1)[3 * x1 + c]};
    range[c] = *std::max_element(values, values + 4) - *std::min_element(values, values + 4);
  }
  return range;
}

// A small lamp 6.4 deg from the zenith, so the north pass carries it over the
// pole of the latitude-longitude maps, and a 0.4-rad blind spot below the
// horizon (rgb 0, validity 0).
inline const glm::dvec3 kZenithLamp = glm::normalize(glm::dvec3(0.1, 0.05, 1.0));
inline constexpr double kZenithLampRadiusRad = 6.0 * M_PI / 180.0;
inline const glm::dvec3 kBlindSpot = glm::normalize(glm::dvec3(0.2, -0.9, -0.4));

inline ibl::CubeMapRGB zenithLampRoom(int face_size, double lamp_gain, std::vector<float>& validity) {
  ibl::CubeMapRGB cube(face_size);
  validity.assign(static_cast<size_t>(ibl::kCubeFaceCount) * face_size * face_size, 1.0f);
  for (int face = 0; face < ibl::kCubeFaceCount; ++face) {
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x) {
        const glm::dvec3 d = ibl::cubeTexelCenterDirection(face, x, y, face_size);
        glm::dvec3 value = analyticEnvironment(d);
        if (glm::dot(d, kZenithLamp) > std::cos(kZenithLampRadiusRad)) value += lamp_gain * glm::dvec3(1.0, 0.9, 0.8);
        if (glm::dot(d, kBlindSpot) > std::cos(0.4)) {
          value = glm::dvec3(0.0);
          validity[static_cast<size_t>(face) * face_size * face_size + static_cast<size_t>(y) * face_size + x] = 0.0f;
        }
        cube.texel(face, x, y) = glm::vec3(value);
      }
    }
  }
  return cube;
}

}  // namespace probelight::test
