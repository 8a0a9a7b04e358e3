#include "model/model_placement.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace probelight::model {
namespace {

// A tetrahedron whose origin is off to one side and above its base.
MeshModel offsetTetrahedron() {
  MeshModel model;
  Primitive p;
  p.positions_m = {{0.1f, 0.2f, -0.3f}, {0.3f, 0.2f, -0.3f}, {0.1f, 0.5f, -0.3f}, {0.15f, 0.25f, 0.1f}};
  p.indices = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
  model.primitives.push_back(p);
  model.min_m = {0.1f, 0.2f, -0.3f};
  model.max_m = {0.3f, 0.5f, 0.1f};
  return model;
}

glm::dvec3 place(const glm::dmat4& world, const glm::vec3& v) {
  return glm::dvec3(world * glm::dvec4(glm::dvec3(v), 1.0));
}

TEST(ModelPlacement, TheLowestPointRestsOnTheGroundWhateverTheTurnAndScale) {
  const MeshModel model = offsetTetrahedron();
  for (const double yaw : {0.0, 0.7, -2.0})
    for (const double scale : {0.5, 1.0, 3.0}) {
      const glm::dmat4 world = worldFromModel(model, {{0.02, -0.04}, yaw, scale});
      double lowest = 1e9;
      for (const glm::vec3& v : model.primitives[0].positions_m) lowest = std::min(lowest, place(world, v).z);
      EXPECT_NEAR(lowest, 0.0, 1e-12) << yaw << " " << scale;
      // The top is the model's height, scaled, above the ground.
      EXPECT_NEAR(place(world, model.primitives[0].positions_m[3]).z, 0.4 * scale, 1e-6) << yaw << " " << scale;
    }
}

TEST(ModelPlacement, TheOriginStandsAtThePositionAndTheModelTurnsCounterClockwise) {
  MeshModel model = offsetTetrahedron();
  const glm::dmat4 world = worldFromModel(model, {{0.02, -0.04}, M_PI / 2.0, 2.0});
  const glm::dvec3 origin(world * glm::dvec4(0.0, 0.0, 0.0, 1.0));
  EXPECT_NEAR(origin.x, 0.02, 1e-12);
  EXPECT_NEAR(origin.y, -0.04, 1e-12);
  EXPECT_NEAR(origin.z, 0.6, 1e-6) << "lifted by 2 x 0.3";
  // +X turns to +Y, scaled by 2.
  const glm::dvec3 x_axis(world * glm::dvec4(1.0, 0.0, 0.0, 0.0));
  EXPECT_NEAR(x_axis.x, 0.0, 1e-12);
  EXPECT_NEAR(x_axis.y, 2.0, 1e-12);
}

TEST(ModelPlacement, TheBoundingSphereHoldsEveryVertexAndNoMoreThanTheBox) {
  const MeshModel model = offsetTetrahedron();
  const glm::dmat4 world = worldFromModel(model, {{0.3, 0.1}, 1.1, 1.7});
  const BoundingSphere sphere = placedBoundingSphere(model, world);
  double farthest = 0.0;
  glm::dvec3 low(1e9), high(-1e9);
  for (const glm::vec3& v : model.primitives[0].positions_m) {
    const glm::dvec3 placed = place(world, v);
    farthest = std::max(farthest, glm::length(placed - sphere.centre_w));
    low = glm::min(low, placed);
    high = glm::max(high, placed);
  }
  EXPECT_NEAR(sphere.radius_m, farthest, 1e-12) << "touches the farthest vertex";
  EXPECT_LE(sphere.radius_m, 0.5 * glm::length(high - low) + 1e-12);
  EXPECT_NEAR(sphere.centre_w.x, 0.5 * (low.x + high.x), 1e-12);
  EXPECT_EQ(placedBoundingSphere(MeshModel{}, world).radius_m, 0.0) << "no vertices: an empty sphere";
}

}  // namespace
}  // namespace probelight::model
