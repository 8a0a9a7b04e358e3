#include "stages/scene_object.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "stages/stage_settings.hpp"

namespace probelight {
namespace {

// One upright triangle standing with its lowest point 0.1 below the model's
// origin, of a material with this roughness.
std::shared_ptr<model::MeshModel> triangleModel(float roughness) {
  auto m = std::make_shared<model::MeshModel>();
  model::Primitive p;
  p.positions_m = {{-0.1f, 0.0f, -0.1f}, {0.1f, 0.0f, -0.1f}, {0.0f, 0.0f, 0.2f}};
  p.indices = {0, 1, 2};
  p.material = 0;
  m->primitives.push_back(p);
  m->materials.emplace_back();
  m->materials[0].roughness_factor = roughness;
  m->min_m = {-0.1f, 0.0f, -0.1f};
  m->max_m = {0.1f, 0.0f, 0.2f};
  return m;
}

// Glossy maps are made only for a roughness between the mirror and the
// diffuse rung (ibl/metallic_roughness.hpp: alphas 0, 0.046, 0.146, 1;
// roughness = sqrt(alpha): 0.21, 0.38, 1): a perfect mirror and glTF's
// fully rough default read none.
TEST(SceneObject, AModelReadsGlossyMapsOnlyForRoughnessBetweenMirrorAndMatte) {
  const std::vector<double> exponents{128.0, 16.0};
  for (const auto& [roughness, reads] : {std::pair{0.0f, false}, {1.0f, false}, {0.8f, true}, {0.1f, true},
                                         {0.3f, true}, {0.5f, true}, {0.95f, true}}) {
    auto m = triangleModel(roughness);
    // Every primitive has a material here, but glTF's default (roughness 1)
    // stands by for those that do not, and must not count on its own.
    EXPECT_EQ(modelReadsGlossy(*m, exponents), reads) << roughness;
    EXPECT_FALSE(modelReadsGlossy(*m, {})) << roughness;
  }
  // A roughness texture whose green spans matte to glossy reads them, even
  // with a matte factor's... factor 1 and G from 0.3 to 1.
  auto textured = triangleModel(1.0f);
  textured->images.push_back({"rough", 2, 1, {0, 77, 0, 255, 0, 255, 0, 255}});
  textured->materials[0].metallic_roughness.image = 0;
  EXPECT_TRUE(modelReadsGlossy(*textured, exponents));
}

// The maps the stages make follow the object shown: with probelight.yaml's
// defaults (the sphere's material a mirror, which reads no glossy map) a
// rough model still gets its glossy levels, and a matte one none. (They
// once followed the sphere's settings alone, so a model of roughness 0.3
// was drawn from the mirror map, as sharp as a roughness of 0.05.)
TEST(SceneObject, GlossyMapsAreMadeForTheObjectShownNotTheSpheresSettings) {
  const PipelineSettings defaults;
  ASSERT_EQ(glossyExponents(defaults).size(), 2u);
  for (const auto& [roughness, levels] : {std::pair{0.3f, 2}, {1.0f, 0}, {0.0f, 0}}) {
    SceneObject object;
    object.model = triangleModel(roughness);
    EXPECT_EQ(environmentMapSettings(defaults, object.readsGlossy(glossyExponents(defaults))).glossy_levels, levels)
        << roughness;
  }
  // The built-in sphere: glossy levels only for a glossiness between mirror and matte.
  SceneObject sphere;
  sphere.material = objectMaterial(defaults);
  EXPECT_EQ(environmentMapSettings(defaults, sphere.readsGlossy(glossyExponents(defaults))).glossy_levels, 0);
  sphere.material.k_reflect = 0.5f;
  sphere.material.glossiness = 0.5f;
  EXPECT_EQ(environmentMapSettings(defaults, sphere.readsGlossy(glossyExponents(defaults))).glossy_levels, 2);
}

TEST(SceneObject, AModelStandsOnTheGroundAndCastsItsOwnTriangles) {
  const SceneObject object = modelSceneObject(triangleModel(0.5f), {{0.02, -0.03}, 0.5 * M_PI, 2.0});
  ASSERT_TRUE(object.isModel());
  ASSERT_EQ(object.shape.shape, ibl::ShadowCaster::Shape::kMesh);
  ASSERT_TRUE(object.shape.mesh_triangles_w);
  ASSERT_EQ(object.shape.mesh_triangles_w->size(), 3u);
  const std::vector<glm::vec3>& t = *object.shape.mesh_triangles_w;
  // Lowest point on the ground, scaled by 2, turned a quarter about +Z:
  // model x becomes world y.
  EXPECT_NEAR(t[0].z, 0.0f, 1e-6f);
  EXPECT_NEAR(t[2].z, 0.6f, 1e-6f);
  EXPECT_NEAR(t[0].x, 0.02f, 1e-6f);
  EXPECT_NEAR(t[0].y, -0.03f - 0.2f, 1e-6f);
  // The bounding sphere holds every vertex, and the CPU reference finds the
  // triangle from either side.
  for (const glm::vec3& v : t)
    EXPECT_LE(glm::length(glm::dvec3(v) - object.shape.mesh_centre_w), object.shape.mesh_radius_m + 1e-9);
  const auto hit = object.shape.intersect({0.5, -0.03, 0.2}, {-1.0, 0.0, 0.0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(*hit, 0.48, 1e-6);
  EXPECT_TRUE(object.shape.intersect({-0.5, -0.03, 0.2}, {1.0, 0.0, 0.0}));
  EXPECT_FALSE(object.shape.intersect({0.5, -0.03, 0.7}, {-1.0, 0.0, 0.0}));  // above it
  EXPECT_FALSE(object.shape.intersect({0.5, -0.03, 0.2}, {1.0, 0.0, 0.0}));   // pointing away
}

TEST(SceneObject, TheConfigsObjectIsTheSphereUnlessItNamesAModel) {
  PipelineSettings settings;
  settings.object.radius_m = 0.05;
  SceneObject object;
  ASSERT_TRUE(sceneObjectFromConfig(settings, object).isOk());
  EXPECT_FALSE(object.isModel());
  EXPECT_EQ(object.shape.shape, ibl::ShadowCaster::Shape::kSphere);
  EXPECT_EQ(object.shape.radius_m, 0.05);
  settings.object.model_path = "/nonexistent/model.glb";
  const Status status = sceneObjectFromConfig(settings, object);
  EXPECT_FALSE(status.isOk());
  EXPECT_NE(status.message().find("/nonexistent/model.glb"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace probelight
