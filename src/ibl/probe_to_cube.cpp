#include "ibl/probe_to_cube.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <thread>
#include <vector>

#include "ibl/color_transfer.hpp"

namespace probelight::ibl {

namespace {

// Bilinear fetch of the 8-bit encoded values, in [0, 1], at a pixel position
// in OpenCV's convention (pixel (u, v)'s centre at integer (u, v), as
// projectToPixel and calibration use), edges clamped: what a GL_LINEAR,
// CLAMP_TO_EDGE texture returns at texcoord = (pixel + 0.5) / size.
glm::dvec3 sampleEncodedBilinear(const ImageRGB8& image, const glm::dvec2& pixel) {
  const double u = pixel.x;
  const double v = pixel.y;
  const double u_floor = std::floor(u);
  const double v_floor = std::floor(v);
  const double fu = u - u_floor;
  const double fv = v - v_floor;
  const int x0 = std::clamp(static_cast<int>(u_floor), 0, image.width - 1);
  const int x1 = std::clamp(static_cast<int>(u_floor) + 1, 0, image.width - 1);
  const int y0 = std::clamp(static_cast<int>(v_floor), 0, image.height - 1);
  const int y1 = std::clamp(static_cast<int>(v_floor) + 1, 0, image.height - 1);
  auto fetch = [&image](int x, int y) {
    const std::uint8_t* p = image.row(y) + static_cast<size_t>(x) * 3u;
    return glm::dvec3(p[0], p[1], p[2]) / 255.0;
  };
  const glm::dvec3 top = glm::mix(fetch(x0, y0), fetch(x1, y0), fu);
  const glm::dvec3 bottom = glm::mix(fetch(x0, y1), fetch(x1, y1), fu);
  return glm::mix(top, bottom, fv);
}

// Same, for a linear float image.
glm::dvec3 sampleLinearBilinear(const ImageRGBF& image, const glm::dvec2& pixel) {
  const double u_floor = std::floor(pixel.x);
  const double v_floor = std::floor(pixel.y);
  const double fu = pixel.x - u_floor;
  const double fv = pixel.y - v_floor;
  const int x0 = std::clamp(static_cast<int>(u_floor), 0, image.width - 1);
  const int x1 = std::clamp(static_cast<int>(u_floor) + 1, 0, image.width - 1);
  const int y0 = std::clamp(static_cast<int>(v_floor), 0, image.height - 1);
  const int y1 = std::clamp(static_cast<int>(v_floor) + 1, 0, image.height - 1);
  auto fetch = [&image](int x, int y) { return glm::dvec3(image.at(x, y)); };
  const glm::dvec3 top = glm::mix(fetch(x0, y0), fetch(x1, y0), fu);
  const glm::dvec3 bottom = glm::mix(fetch(x0, y1), fetch(x1, y1), fu);
  return glm::mix(top, bottom, fv);
}

// Every texel whose direction the ball shows gets sampleLinear(pixel) /
// reflectance; the blind spot stays 0. With samples_per_axis k > 1 a texel
// takes as many samples a side as the pixels it spans (its corners'
// distance in the image, rounded up, at most k): near the ball's middle a
// texel is a fraction of a pixel and its centre says all (the bilinear
// fetch already mixes the pixels around it), near the rim it spans several
// and each needs a sample. Faces are shared among the machine's cores.
template <typename SampleLinear>
CubeMapRGB ballToCube(const MirrorBallView& view, const ProbeToCubeParams& params, SampleLinear sample_linear) {
  CubeMapRGB cube(params.face_size);
  const double inverse_reflectance = params.probe_reflectance > 0.0 ? 1.0 / params.probe_reflectance : 0.0;
  const int k_max = std::max(1, params.samples_per_axis);
  const int n = params.face_size;
  const double size = n;
  auto doFace = [&](int face) {
    // Texel corners in the image (k_max > 1 only); nullopt: the blind spot.
    std::vector<std::optional<glm::dvec2>> corners;
    if (k_max > 1) {
      corners.resize(static_cast<std::size_t>(n + 1) * (n + 1));
      for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x)
          corners[static_cast<std::size_t>(y) * (n + 1) + x] = reflectedDirectionToPixel(
              view, cubeCoordToDirection({face, x / size, y / size}), params.normal_iterations);
    }
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        int k = 1;
        if (k_max > 1) {
          const auto& c00 = corners[static_cast<std::size_t>(y) * (n + 1) + x];
          const auto& c10 = corners[static_cast<std::size_t>(y) * (n + 1) + x + 1];
          const auto& c01 = corners[static_cast<std::size_t>(y + 1) * (n + 1) + x];
          const auto& c11 = corners[static_cast<std::size_t>(y + 1) * (n + 1) + x + 1];
          if (!c00 || !c10 || !c01 || !c11) {
            k = k_max;  // at the blind spot's edge: as many as allowed
          } else {
            const double span_px = std::max({glm::length(*c10 - *c00), glm::length(*c01 - *c00),
                                             glm::length(*c11 - *c10), glm::length(*c11 - *c01)});
            k = std::clamp(static_cast<int>(std::ceil(span_px)), 1, k_max);
          }
        }
        glm::dvec3 sum(0.0);
        int seen = 0;
        for (int j = 0; j < k; ++j)
          for (int i = 0; i < k; ++i) {
            const glm::dvec3 direction_w =
                k == 1 ? cubeTexelCenterDirection(face, x, y, n)
                       : cubeCoordToDirection({face, (x + (i + 0.5) / k) / size, (y + (j + 0.5) / k) / size});
            const auto pixel = reflectedDirectionToPixel(view, direction_w, params.normal_iterations);
            if (!pixel) continue;  // the blind spot
            sum += sample_linear(*pixel);
            ++seen;
          }
        if (seen > 0) cube.texel(face, x, y) = glm::vec3(sum / static_cast<double>(seen) * inverse_reflectance);
      }
  };
  const int threads = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, kCubeFaceCount);
  if (threads == 1 || n < 16) {
    for (int face = 0; face < kCubeFaceCount; ++face) doFace(face);
    return cube;
  }
  // Each face is written by one thread only.
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t)
    workers.emplace_back([&, t] {
      for (int face = t; face < kCubeFaceCount; face += threads) doFace(face);
    });
  for (std::thread& worker : workers) worker.join();
  return cube;
}

}  // namespace

CubeMapRGB probeImageToCubeMap(const MirrorBallView& view, const ImageRGB8& image, const ProbeToCubeParams& params) {
  if (image.empty()) return CubeMapRGB(params.face_size);
  const CameraTransfer& transfer = params.camera_transfer;
  return ballToCube(view, params, [&](const glm::dvec2& pixel) {
    // Encoded values are interpolated, then decoded: what the GPU stage does.
    const glm::dvec3 encoded = sampleEncodedBilinear(image, pixel);
    return glm::dvec3{decodeCameraValue(transfer, encoded.r), decodeCameraValue(transfer, encoded.g),
                      decodeCameraValue(transfer, encoded.b)};
  });
}

CubeMapRGB probeRadianceToCubeMap(const MirrorBallView& view, const ImageRGBF& linear, const ProbeToCubeParams& params) {
  if (linear.empty()) return CubeMapRGB(params.face_size);
  return ballToCube(view, params, [&](const glm::dvec2& pixel) { return sampleLinearBilinear(linear, pixel); });
}

}  // namespace probelight::ibl
