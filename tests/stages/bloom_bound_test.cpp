// The bloom's skip (stages/bloom_bound.hpp): the bound is never below the
// sphere's shading (ibl::shadeSurface, the CPU twin of sphere_object.frag)
// anywhere on it, for maps whose brightest texel is the peak given; and it
// says "nothing above white" only when that holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "model/mesh_model.hpp"
#include "stages/bloom_bound.hpp"

namespace probelight {
namespace {

ibl::CubeMapRGB randomMap(int face_size, double peak, std::mt19937& random) {
  std::uniform_real_distribution<float> value(0.0f, static_cast<float>(peak));
  ibl::CubeMapRGB map(face_size);
  for (auto& face : map.faces)
    for (glm::vec3& texel : face) texel = glm::vec3(value(random), value(random), value(random));
  // The peak itself somewhere.
  map.faces[2][5] = glm::vec3(static_cast<float>(peak));
  return map;
}

glm::vec3 randomUnit(std::mt19937& random) {
  std::normal_distribution<float> normal(0.0f, 1.0f);
  return glm::normalize(glm::vec3(normal(random), normal(random), normal(random)));
}

TEST(BloomBound, NeverBelowTheSpheresShading) {
  std::mt19937 random(7);
  SceneObject object;
  object.material.albedo = glm::vec3(0.9f, 0.6f, 0.3f);
  object.material.ambient = 0.3f;
  object.material.k_diffuse = 0.8f;
  object.material.k_specular = 0.5f;
  object.material.shininess = 8.0f;
  object.material.k_reflect = 0.4f;
  ibl::SceneLighting lighting;
  lighting.ambient_rgb = glm::vec3(0.2f, 0.25f, 0.3f);
  lighting.highlight_rgb = glm::vec3(1.5f, 1.2f, 0.9f);
  lighting.highlight_direction_w = glm::normalize(glm::vec3(0.3f, -0.2f, 1.0f));
  lighting.clipped_direction_w[0] = glm::normalize(glm::vec3(0.0f, 0.5f, 1.0f));
  lighting.clipped_diffuse_rgb[0] = glm::vec3(0.7f, 0.6f, 0.5f);
  const double peak = 1.3;
  const ibl::CubeMapRGB reflection = randomMap(8, peak, random);
  const ibl::CubeMapRGB diffuse = randomMap(4, peak, random);
  const glm::dvec3 gain(0.8, 1.0, 1.2);
  const double bound = objectLightBound(object, lighting, peak, gain);
  double highest = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const glm::vec3 shaded =
        ibl::shadeSurface(randomUnit(random), randomUnit(random), diffuse, reflection, object.material, lighting);
    const glm::dvec3 out = glm::dvec3(shaded) * gain;
    highest = std::max({highest, out.r, out.g, out.b});
  }
  EXPECT_LE(highest, bound);
  // And not so loose that it never skips: within the sum of the terms'
  // peaks, which the sampled normals approach.
  EXPECT_GT(highest, 0.5 * bound);
}

TEST(BloomBound, SaysNothingAboveWhiteOnlyWhenNothingCanBe) {
  SceneObject object;  // the default matte sphere: k_d 1, albedo 0.8
  ibl::SceneLighting lighting;
  // Maps at most 1.0: 0.8 of it at most.
  EXPECT_LE(objectLightBound(object, lighting, 1.0, glm::dvec3(1.0)), 1.0);
  // A clipped light of 0.5 on top of it can reach 1.2.
  lighting.clipped_diffuse_rgb[1] = glm::vec3(0.5f);
  EXPECT_NEAR(objectLightBound(object, lighting, 1.0, glm::dvec3(1.0)), 1.2, 1e-6);
  // Auto exposure two stops down takes it under white again.
  EXPECT_NEAR(objectLightBound(object, lighting, 1.0, glm::dvec3(0.25)), 0.3, 1e-6);
  // A glossy highlight of 2 with k_s 0.5 is at white and above.
  ibl::SceneLighting highlight;
  object.material.k_specular = 0.5f;
  highlight.highlight_rgb = glm::vec3(3.0f, 1.0f, 1.0f);
  EXPECT_GT(objectLightBound(object, highlight, 0.1, glm::dvec3(1.0)), 1.0);
}

TEST(BloomBound, AModelsEmissiveAndReflectionsCount) {
  auto model = std::make_shared<model::MeshModel>();
  model->materials.emplace_back();
  model->materials.back().emissive_factor = glm::vec3(0.0f, 2.5f, 0.0f);
  SceneObject object;
  object.model = model;
  ibl::SceneLighting lighting;
  // A glowing part at 2.5 is above white whatever the room.
  EXPECT_GE(objectLightBound(object, lighting, 0.0, glm::dvec3(1.0)), 2.5);
  // Without it, a dark room's maps (peak 0.2) keep the model at white at
  // most (a mix of diffuse and specular, the floor it may reflect white at
  // most): nothing above white.
  model->materials.back().emissive_factor = glm::vec3(0.0f);
  EXPECT_LE(objectLightBound(object, lighting, 0.2, glm::dvec3(1.0)), 1.0);
  // A clipped lamp of 1.5 lights its diffuse term above white.
  lighting.clipped_diffuse_rgb[0] = glm::vec3(1.5f);
  EXPECT_GT(objectLightBound(object, lighting, 0.2, glm::dvec3(1.0)), 1.0);
}

}  // namespace
}  // namespace probelight
