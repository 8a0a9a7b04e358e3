#include "ibl/irradiance.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

// For L(w) = a + b.w the cosine integral is closed form:
//   E(n) = pi * a + (2 pi / 3) * b.n
// (the SH band weights A0 = pi and A1 = 2 pi / 3 of Ramamoorthi & Hanrahan).
TEST(Irradiance, LinearRadianceGivesTheClosedForm) {
  const double a = 0.7;
  const glm::dvec3 b(0.1, -0.2, 0.4);
  const int face_size = 32;
  CubeMapRGB cube(face_size);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x) {
        cube.texel(face, x, y) = glm::vec3(static_cast<float>(a + glm::dot(b, cubeTexelCenterDirection(face, x, y, face_size))));
      }
    }
  }
  for (const glm::dvec3& n : testing::fibonacciDirections(40)) {
    const double expected = M_PI * a + 2.0 * M_PI / 3.0 * glm::dot(b, n);
    // Midpoint quadrature of an integrand with a kink (the horizon) that cuts
    // texels: error ~ one texel's share of the kink, (2/32)^2 relative ~ 0.4%;
    // 1% of pi * a (0.022) bounds it.
    EXPECT_NEAR(irradianceFromCubeMap(cube, n).r, expected, 0.01 * M_PI * a);
  }
}

TEST(Irradiance, ConstantRadianceGivesPiTimesRadianceWhereTheHorizonFollowsEdges) {
  const int face_size = 16;
  CubeMapRGB cube(face_size);
  for (auto& face : cube.faces) face.assign(face.size(), glm::vec3(1.0f, 2.0f, 0.5f));
  // For n = +Z the horizon runs along texel edges, so the midpoint rule has
  // only its smooth O(h^2) error: (2/16)^2 / 24 * (curvature ~2) ~ 1e-3 relative.
  const glm::dvec3 e = irradianceFromCubeMap(cube, {0, 0, 1});
  EXPECT_NEAR(e.r / M_PI, 1.0, 2e-3);
  EXPECT_NEAR(e.g / M_PI, 2.0, 4e-3);
  EXPECT_NEAR(e.b / M_PI, 0.5, 1e-3);
}

}  // namespace
}  // namespace probelight::ibl
