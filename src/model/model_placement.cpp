#include "model/model_placement.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::model {

glm::dmat4 worldFromModel(const MeshModel& model, const ModelPlacement& placement) {
  const double c = std::cos(placement.yaw_rad), s = std::sin(placement.yaw_rad), k = placement.scale;
  glm::dmat4 world(1.0);  // columns
  world[0] = glm::dvec4(k * c, k * s, 0.0, 0.0);
  world[1] = glm::dvec4(-k * s, k * c, 0.0, 0.0);
  world[2] = glm::dvec4(0.0, 0.0, k, 0.0);
  world[3] = glm::dvec4(placement.position_m, -k * static_cast<double>(model.min_m.z), 1.0);
  return world;
}

BoundingSphere placedBoundingSphere(const MeshModel& model, const glm::dmat4& world_from_model) {
  BoundingSphere sphere;
  bool any = false;
  glm::dvec3 low(0.0), high(0.0);
  for (const Primitive& primitive : model.primitives)
    for (const glm::vec3& vertex : primitive.positions_m) {
      const glm::dvec3 placed(world_from_model * glm::dvec4(glm::dvec3(vertex), 1.0));
      low = any ? glm::min(low, placed) : placed;
      high = any ? glm::max(high, placed) : placed;
      any = true;
    }
  if (!any) return sphere;
  sphere.centre_w = 0.5 * (low + high);
  double radius_squared = 0.0;
  for (const Primitive& primitive : model.primitives)
    for (const glm::vec3& vertex : primitive.positions_m) {
      const glm::dvec3 placed(world_from_model * glm::dvec4(glm::dvec3(vertex), 1.0));
      const glm::dvec3 offset = placed - sphere.centre_w;
      radius_squared = std::max(radius_squared, glm::dot(offset, offset));
    }
  sphere.radius_m = std::sqrt(radius_squared);
  return sphere;
}

}  // namespace probelight::model
