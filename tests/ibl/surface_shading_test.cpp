#include "ibl/surface_shading.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace probelight::ibl {
namespace {

CubeMapRGB constantCube(const glm::vec3& value) {
  CubeMapRGB cube(4);
  for (auto& face : cube.faces) face.assign(face.size(), value);
  return cube;
}

// All terms are a few float operations on values near 1: 1e-5 is ~100 ulp.
constexpr float kTolerance = 1e-5f;

TEST(SurfaceShading, ConstantMapsGiveTheClosedForm) {
  const glm::vec3 diffuse_rgb(0.3f, 0.4f, 0.5f);
  const glm::vec3 reflection_rgb(0.9f, 0.1f, 0.2f);
  SurfaceMaterial material;
  material.albedo = {0.5f, 0.6f, 0.7f};
  material.ambient = 0.25f;
  material.k_diffuse = 0.8f;
  material.k_specular = 0.5f;
  material.shininess = 16.0f;
  material.k_reflect = 0.3f;
  SceneLighting lighting;
  lighting.ambient_rgb = {0.2f, 0.2f, 0.4f};
  lighting.highlight_direction_w = {0.0f, 0.0f, 1.0f};
  lighting.highlight_rgb = {1.0f, 0.9f, 0.8f};
  // Eye 45 deg off the normal, light along it: the half vector is 22.5 deg off.
  const glm::vec3 normal(0.0f, 0.0f, 1.0f);
  const glm::vec3 to_eye = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f));
  const float highlight = std::pow(static_cast<float>(std::cos(M_PI / 8.0)), 16.0f);
  const glm::vec3 expected = lighting.ambient_rgb * 0.25f + 0.8f * diffuse_rgb * material.albedo +
                             0.5f * highlight * lighting.highlight_rgb + 0.3f * reflection_rgb;
  const glm::vec3 shaded =
      shadeSurface(normal, to_eye, constantCube(diffuse_rgb), constantCube(reflection_rgb), material, lighting);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(shaded[c], expected[c], kTolerance) << "channel " << c;
}

TEST(SurfaceShading, MapsAreReadAtTheNormalAndTheMirrorDirection) {
  CubeMapRGB diffuse = constantCube(glm::vec3(0.0f));
  CubeMapRGB reflection = constantCube(glm::vec3(0.0f));
  diffuse.faces[2].assign(diffuse.faces[2].size(), glm::vec3(1.0f, 0.0f, 0.0f));        // +Y
  reflection.faces[1].assign(reflection.faces[1].size(), glm::vec3(0.0f, 1.0f, 0.0f));  // -X
  SurfaceMaterial material;
  material.albedo = glm::vec3(1.0f);
  material.k_diffuse = 1.0f;
  material.k_reflect = 1.0f;
  const SceneLighting no_lamps;
  // Normal +Y; the eye sits toward +X, so the mirror direction heads to -X.
  const glm::vec3 normal(0.0f, 1.0f, 0.0f);
  const glm::vec3 to_eye = glm::normalize(glm::vec3(1.0f, 0.3f, 0.0f));
  const glm::vec3 shaded = shadeSurface(normal, to_eye, diffuse, reflection, material, no_lamps);
  EXPECT_NEAR(shaded.r, 1.0f, kTolerance);
  EXPECT_NEAR(shaded.g, 1.0f, kTolerance);
  EXPECT_NEAR(shaded.b, 0.0f, kTolerance);
}

TEST(SurfaceShading, HighlightVanishesWhenTheHalfVectorFacesAway) {
  SurfaceMaterial material;
  material.k_diffuse = 0.0f;
  material.k_specular = 1.0f;
  SceneLighting lighting;
  lighting.highlight_rgb = glm::vec3(1.0f);
  lighting.highlight_direction_w = {0.0f, 0.0f, -1.0f};
  const glm::vec3 shaded = shadeSurface({0, 0, 1}, glm::normalize(glm::vec3(0.1f, 0.0f, -1.0f)), constantCube({}),
                                        constantCube({}), material, lighting);
  EXPECT_EQ(shaded, glm::vec3(0.0f));
}

}  // namespace
}  // namespace probelight::ibl
