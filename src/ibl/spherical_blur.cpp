#include "ibl/spherical_blur.hpp"

#include <cmath>
#include <vector>

namespace probelight::ibl {

glm::dvec3 blurTangent(const glm::dvec3& n, BlurAxis axis) {
  const glm::dvec3 across_meridian = glm::cross(glm::dvec3(0.0, 0.0, 1.0), n);
  // At the poles "east" is undefined; any fixed tangent will do there.
  const glm::dvec3 east =
      glm::length(across_meridian) < 1e-4 ? glm::dvec3(1.0, 0.0, 0.0) : glm::normalize(across_meridian);
  return axis == BlurAxis::kEast ? east : glm::cross(n, east);
}

CubeMapRGB sphericalBlurPass(const CubeMapRGB& input, int output_face_size, const SphericalBlurPass& pass) {
  CubeMapRGB output(output_face_size);
  const int tap_count = 2 * pass.half_taps + 1;
  const double step_rad = pass.half_taps > 0 ? 3.0 * pass.sigma_rad / pass.half_taps : 0.0;
  std::vector<double> angle_rad(tap_count);
  std::vector<double> weight(tap_count);
  double weight_sum = 0.0;
  for (int k = 0; k < tap_count; ++k) {
    const int i = k - pass.half_taps;
    angle_rad[k] = i * step_rad;
    weight[k] = pass.sigma_rad > 0.0 ? std::exp(-angle_rad[k] * angle_rad[k] / (2.0 * pass.sigma_rad * pass.sigma_rad))
                                     : (i == 0 ? 1.0 : 0.0);
    weight_sum += weight[k];
  }
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < output_face_size; ++y) {
      for (int x = 0; x < output_face_size; ++x) {
        const glm::dvec3 n = cubeTexelCenterDirection(face, x, y, output_face_size);
        const glm::dvec3 t = blurTangent(n, pass.axis);
        glm::dvec3 sum(0.0);
        for (int k = 0; k < tap_count; ++k) {
          const glm::dvec3 direction = std::cos(angle_rad[k]) * n + std::sin(angle_rad[k]) * t;
          sum += weight[k] * glm::dvec3(input.sampleBilinear(direction));
        }
        output.texel(face, x, y) = glm::vec3(sum / weight_sum);
      }
    }
  }
  return output;
}

}  // namespace probelight::ibl
