#include "sim/occluder.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "sim/gltf_brdf.hpp"
#include "sim/scene_geometry.hpp"

namespace probelight::sim {
namespace {

// Same self-hit guard as intersectSphere: a ray that starts on the surface
// does not hit it again at t = 0.
constexpr double kMinHitDistance_m = 1e-9;

double yawRad(const VirtualOccluder& box) { return box.box_yaw_deg * std::numbers::pi / 180.0; }

}  // namespace

glm::dvec3 boxCenterWorld(const VirtualOccluder& box) {
  return {box.position_w.x, box.position_w.y, 0.5 * box.box_size_m.z};
}

glm::dvec3 boxLocalFromWorldDirection(const VirtualOccluder& box, const glm::dvec3& dir_w) {
  const double c = std::cos(yawRad(box)), s = std::sin(yawRad(box));
  return {c * dir_w.x + s * dir_w.y, -s * dir_w.x + c * dir_w.y, dir_w.z};
}

glm::dvec3 boxWorldFromLocalDirection(const VirtualOccluder& box, const glm::dvec3& dir_local) {
  const double c = std::cos(yawRad(box)), s = std::sin(yawRad(box));
  return {c * dir_local.x - s * dir_local.y, s * dir_local.x + c * dir_local.y, dir_local.z};
}

VirtualOccluder meshOccluder(std::shared_ptr<const model::MeshModel> model, const glm::dmat4& world_from_model) {
  VirtualOccluder mesh;
  mesh.shape = VirtualOccluder::Shape::kMesh;
  mesh.triangles = std::make_shared<const TriangleScene>(*model, world_from_model);
  for (const model::Material& material : model->materials)
    mesh.has_mask_material = mesh.has_mask_material || material.alpha_mode == model::AlphaMode::kMask;
  mesh.model = std::move(model);
  const WorldBounds bounds = mesh.triangles->bounds();
  if (!bounds.empty()) mesh.position_w = 0.5 * glm::dvec2(bounds.min_w + bounds.max_w);
  return mesh;
}

std::optional<TriangleHit> intersectMesh(const VirtualOccluder& mesh, const glm::dvec3& origin, const glm::dvec3& dir,
                                         double t_max) {
  if (!mesh.triangles) return std::nullopt;
  glm::dvec3 from = origin;
  double travelled = 0.0;
  // A MASK hole: go on from just past it. Bounded, so that a ray along a
  // stack of coplanar holes cannot loop.
  for (int hole = 0; hole < 64; ++hole) {
    std::optional<TriangleHit> hit = mesh.triangles->intersect(from, dir, t_max - travelled);
    if (!hit) return std::nullopt;
    const model::Material* material =
        hit->material >= 0 && hit->material < static_cast<int>(mesh.model->materials.size())
            ? &mesh.model->materials[static_cast<std::size_t>(hit->material)]
            : nullptr;
    if (!material || material->alpha_mode != model::AlphaMode::kMask ||
        surfaceAt(*mesh.model, *hit).alpha >= material->alpha_cutoff) {
      hit->t += travelled;
      return hit;
    }
    travelled += hit->t;
    from = origin + travelled * dir;
  }
  return std::nullopt;
}

bool occluderBlocks(const VirtualOccluder& occluder, const glm::dvec3& origin, const glm::dvec3& dir, double t_max) {
  if (occluder.shape == VirtualOccluder::Shape::kMesh) {
    if (!occluder.triangles) return false;
    if (!occluder.has_mask_material) return occluder.triangles->occluded(origin, dir, t_max);
    return intersectMesh(occluder, origin, dir, t_max).has_value();
  }
  const std::optional<double> t = intersectOccluder(occluder, origin, dir);
  return t && *t < t_max;
}

OccluderBound occluderBound(const VirtualOccluder& occluder) {
  if (occluder.shape == VirtualOccluder::Shape::kMesh) {
    const WorldBounds bounds = occluder.triangles ? occluder.triangles->bounds() : WorldBounds{};
    if (bounds.empty()) return {glm::dvec3(occluder.position_w, 0.0), 0.0};
    return {0.5 * (bounds.min_w + bounds.max_w), 0.5 * glm::length(bounds.max_w - bounds.min_w)};
  }
  if (occluder.shape == VirtualOccluder::Shape::kSphere)
    return {{occluder.position_w.x, occluder.position_w.y, occluder.radius_m}, occluder.radius_m};
  return {boxCenterWorld(occluder), 0.5 * glm::length(occluder.box_size_m)};
}

std::optional<double> intersectOccluder(const VirtualOccluder& occluder, const glm::dvec3& origin, const glm::dvec3& dir,
                                        glm::dvec3* normal_out) {
  if (occluder.shape == VirtualOccluder::Shape::kMesh) {
    const std::optional<TriangleHit> hit =
        intersectMesh(occluder, origin, dir, std::numeric_limits<double>::infinity());
    if (!hit) return std::nullopt;
    if (normal_out) *normal_out = hit->back_face ? -hit->shading_normal : hit->shading_normal;
    return hit->t;
  }
  if (occluder.shape == VirtualOccluder::Shape::kSphere) {
    const glm::dvec3 center{occluder.position_w.x, occluder.position_w.y, occluder.radius_m};
    auto t = intersectSphere(origin, dir, center, occluder.radius_m);
    if (t && normal_out) *normal_out = (origin + *t * dir - center) / occluder.radius_m;
    return t;
  }
  // Slab method in the box's own frame, where it is axis-aligned.
  const glm::dvec3 half_m = 0.5 * occluder.box_size_m;
  const glm::dvec3 o = boxLocalFromWorldDirection(occluder, origin - boxCenterWorld(occluder));
  const glm::dvec3 d = boxLocalFromWorldDirection(occluder, dir);
  double t_enter = -std::numeric_limits<double>::infinity(), t_exit = std::numeric_limits<double>::infinity();
  glm::dvec3 enter_normal(0.0), exit_normal(0.0);
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] == 0.0) {
      // Parallel to this slab: inside it for every t, or never.
      if (o[axis] < -half_m[axis] || o[axis] > half_m[axis]) return std::nullopt;
      continue;
    }
    double t_near = (-half_m[axis] - o[axis]) / d[axis];
    double t_far = (half_m[axis] - o[axis]) / d[axis];
    // Moving toward +axis, the ray enters through the -axis face.
    const double enter_sign = d[axis] > 0.0 ? -1.0 : 1.0;
    if (t_near > t_far) std::swap(t_near, t_far);
    if (t_near > t_enter) {
      t_enter = t_near;
      enter_normal = glm::dvec3(0.0);
      enter_normal[axis] = enter_sign;
    }
    if (t_far < t_exit) {
      t_exit = t_far;
      exit_normal = glm::dvec3(0.0);
      exit_normal[axis] = -enter_sign;
    }
  }
  if (t_enter > t_exit) return std::nullopt;
  double t = t_enter;
  glm::dvec3 normal_local = enter_normal;
  if (t <= kMinHitDistance_m) {  // the origin is inside (or on) the box: it leaves through the exit face
    t = t_exit;
    normal_local = exit_normal;
  }
  if (t <= kMinHitDistance_m) return std::nullopt;
  if (normal_out) *normal_out = boxWorldFromLocalDirection(occluder, normal_local);
  return t;
}

}  // namespace probelight::sim
