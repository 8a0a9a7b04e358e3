#include "ibl/cube_map.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

// The GLES 2.0 table (section 3.7.5), written out as axes rather than code:
// face direction = major + sc * s_axis + tc * t_axis, sc = 2s - 1, tc = 2t - 1.
struct FaceAxes {
  glm::dvec3 major;
  glm::dvec3 s_axis;
  glm::dvec3 t_axis;
};
const FaceAxes kGlesFaceTable[kCubeFaceCount] = {
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},   // +X: sc = -rz, tc = -ry
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},   // -X: sc = +rz, tc = -ry
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},     // +Y: sc = +rx, tc = +rz
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},   // -Y: sc = +rx, tc = -rz
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},    // +Z: sc = +rx, tc = -ry
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}},  // -Z: sc = -rx, tc = -ry
};

glm::dvec3 tableDirection(int face, double s, double t) {
  const FaceAxes& axes = kGlesFaceTable[face];
  return glm::normalize(axes.major + (2 * s - 1) * axes.s_axis + (2 * t - 1) * axes.t_axis);
}

// Directions are built from a handful of double operations: 1e-12 is many
// rounding steps above what they accumulate, and far below anything a texel sees.
constexpr double kDirectionTolerance = 1e-12;

void expectNearVec(const glm::dvec3& actual, const glm::dvec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

TEST(CubeMap, FaceCentresAreTheAxesInGlOrder) {
  for (int face = 0; face < kCubeFaceCount; ++face) {
    expectNearVec(cubeCoordToDirection({face, 0.5, 0.5}), kGlesFaceTable[face].major, kDirectionTolerance);
  }
  expectNearVec(cubeCoordToDirection({0, 0.5, 0.5}), {1, 0, 0}, kDirectionTolerance);
  expectNearVec(cubeCoordToDirection({4, 0.5, 0.5}), {0, 0, 1}, kDirectionTolerance);  // world up is +Z
}

TEST(CubeMap, SIncreasesTowardMinusZOnThePlusXFace) {
  const glm::dvec3 low_s = cubeCoordToDirection({0, 0.25, 0.5});
  const glm::dvec3 high_s = cubeCoordToDirection({0, 0.75, 0.5});
  EXPECT_GT(low_s.z, 0.0);
  EXPECT_LT(high_s.z, 0.0);
  // t increases toward -Y on +X.
  EXPECT_LT(cubeCoordToDirection({0, 0.5, 0.9}).y, 0.0);
}

TEST(CubeMap, EveryFaceFollowsTheGlesTableBothWays) {
  const double coords[] = {0.0, 0.1, 0.37, 0.5, 0.81, 1.0};
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (double s : coords) {
      for (double t : coords) {
        const glm::dvec3 expected = tableDirection(face, s, t);
        expectNearVec(cubeCoordToDirection({face, s, t}), expected, kDirectionTolerance);
        const bool on_edge = s == 0.0 || s == 1.0 || t == 0.0 || t == 1.0;
        if (on_edge) continue;  // ties are checked separately
        const CubeTexelCoord coord = directionToCubeCoord(expected * 3.7);  // any length works
        EXPECT_EQ(coord.face, face);
        EXPECT_NEAR(coord.s, s, kDirectionTolerance);
        EXPECT_NEAR(coord.t, t, kDirectionTolerance);
      }
    }
  }
}

TEST(CubeMap, TiesPickZThenYThenXAsMesaDoes) {
  EXPECT_EQ(directionToCubeCoord({1, 1, 1}).face, 4);
  EXPECT_EQ(directionToCubeCoord({-1, -1, -1}).face, 5);
  EXPECT_EQ(directionToCubeCoord({1, 0, -1}).face, 5);
  EXPECT_EQ(directionToCubeCoord({0, 1, 1}).face, 4);
  EXPECT_EQ(directionToCubeCoord({1, 1, 0}).face, 2);
  EXPECT_EQ(directionToCubeCoord({-1, -1, 0.5}).face, 3);
}

TEST(CubeMap, TexelCentresEdgesAndCornersRoundTrip) {
  for (int face_size : {1, 2, 7, 16}) {
    for (int face = 0; face < kCubeFaceCount; ++face) {
      for (int y = 0; y < face_size; ++y) {
        for (int x = 0; x < face_size; ++x) {
          const glm::dvec3 direction = cubeTexelCenterDirection(face, x, y, face_size);
          EXPECT_NEAR(glm::length(direction), 1.0, kDirectionTolerance);
          const CubeTexelCoord coord = directionToCubeCoord(direction);
          EXPECT_EQ(coord.face, face);
          EXPECT_NEAR(coord.s * face_size - 0.5, x, 1e-9);
          EXPECT_NEAR(coord.t * face_size - 0.5, y, 1e-9);
        }
      }
    }
  }
  // On edges and corners the face may change (ties), the direction may not.
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (double s : {0.0, 0.5, 1.0}) {
      for (double t : {0.0, 0.5, 1.0}) {
        const glm::dvec3 direction = cubeCoordToDirection({face, s, t});
        expectNearVec(cubeCoordToDirection(directionToCubeCoord(direction)), direction, kDirectionTolerance);
      }
    }
  }
}

TEST(CubeMap, SolidAnglesSumToFourPiAndMatchTheAreaElement) {
  for (int face_size : {1, 3, 16, 64}) {
    double total_sr = 0.0;
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x) total_sr += cubeTexelSolidAngle(x, y, face_size);
    }
    // The atan formula telescopes exactly, so only summation rounding remains.
    EXPECT_NEAR(kCubeFaceCount * total_sr, 4.0 * M_PI, 1e-11) << "face size " << face_size;
  }
  // Small texels approach area * cos^3 / r^2 = (2/n)^2 / (1 + x^2 + y^2)^1.5 with
  // relative error O(1/n^2); at n = 256 that is below 1e-4.
  const int n = 256;
  for (auto [x, y] : {std::pair{0, 0}, std::pair{128, 128}, std::pair{255, 3}}) {
    const double u = 2.0 * (x + 0.5) / n - 1.0;
    const double v = 2.0 * (y + 0.5) / n - 1.0;
    const double approx_sr = (2.0 / n) * (2.0 / n) / std::pow(1.0 + u * u + v * v, 1.5);
    EXPECT_NEAR(cubeTexelSolidAngle(x, y, n) / approx_sr, 1.0, 1e-4);
  }
}

CubeMapRGB cubeWithDistinctTexels(int face_size) {
  CubeMapRGB cube(face_size);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x) cube.texel(face, x, y) = glm::vec3(face, x, y);
    }
  }
  return cube;
}

TEST(CubeMap, NearestPicksTheTexelContainingTheDirection) {
  const CubeMapRGB cube = cubeWithDistinctTexels(8);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    // 0.3 texel off the centre is still inside the texel.
    const glm::vec3 value = cube.sampleNearest(cubeCoordToDirection({face, (5 + 0.8) / 8, (2 + 0.2) / 8}));
    EXPECT_EQ(value, glm::vec3(face, 5, 2));
  }
  // Texel row y = 0 is t near 0: on +Z that is toward world +Y.
  EXPECT_EQ(cube.sampleNearest({0.0, 0.99, 1.0}).z, 0.0f);
}

TEST(CubeMap, BilinearInterpolatesBetweenCentresAndClampsAtFaceEdges) {
  const CubeMapRGB cube = cubeWithDistinctTexels(8);
  // Values are small integers and weights are powers of two: float is exact,
  // except for the direction round trip, which moves s by ~1e-16 (1e-5 is ample).
  constexpr float kTolerance = 1e-5f;
  for (int face = 0; face < kCubeFaceCount; ++face) {
    const glm::vec3 at_centre = cube.sampleBilinear(cubeTexelCenterDirection(face, 3, 6, 8));
    EXPECT_NEAR(at_centre.y, 3.0f, kTolerance);
    EXPECT_NEAR(at_centre.z, 6.0f, kTolerance);
    const glm::vec3 between = cube.sampleBilinear(cubeCoordToDirection({face, 4.0 / 8, 6.5 / 8}));
    EXPECT_NEAR(between.y, 3.5f, kTolerance);
    EXPECT_NEAR(between.z, 6.0f, kTolerance);
    EXPECT_NEAR(between.x, static_cast<float>(face), kTolerance);
    // Within half a texel of the edge GLES2 clamps to the edge texel (no seamless filtering).
    const glm::vec3 at_edge = cube.sampleBilinear(cubeCoordToDirection({face, 0.02, 0.98}));
    EXPECT_NEAR(at_edge.y, 0.0f, kTolerance);
    EXPECT_NEAR(at_edge.z, 7.0f, kTolerance);
  }
}

}  // namespace
}  // namespace probelight::ibl
