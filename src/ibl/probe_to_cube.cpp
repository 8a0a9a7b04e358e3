#include "ibl/probe_to_cube.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace

CubeMapRGB probeImageToCubeMap(const MirrorBallView& view, const ImageRGB8& image, const ProbeToCubeParams& params) {
  CubeMapRGB cube(params.face_size);
  if (image.empty()) return cube;
  const double inverse_reflectance = params.probe_reflectance > 0.0 ? 1.0 / params.probe_reflectance : 0.0;
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < params.face_size; ++y) {
      for (int x = 0; x < params.face_size; ++x) {
        const glm::dvec3 direction_w = cubeTexelCenterDirection(face, x, y, params.face_size);
        const auto pixel = reflectedDirectionToPixel(view, direction_w, params.normal_iterations);
        if (!pixel) continue;  // blind spot: stays 0
        const glm::dvec3 encoded = sampleEncodedBilinear(image, *pixel);
        const CameraTransfer& transfer = params.camera_transfer;
        const glm::dvec3 linear{decodeCameraValue(transfer, encoded.r), decodeCameraValue(transfer, encoded.g),
                                decodeCameraValue(transfer, encoded.b)};
        cube.texel(face, x, y) = glm::vec3(linear * inverse_reflectance);
      }
    }
  }
  return cube;
}

}  // namespace probelight::ibl
