// Virtual objects standing on the ground, for the truth of the shadows they
// cast (World::groundShadow) and for frames that show them
// (World::renderWithOccluders). Plain geometry: no lighting here.
#pragma once

#include <optional>

#include <glm/glm.hpp>

namespace probelight::sim {

// A virtual object standing on the ground (z = 0) in W, for the shadow truth.
struct VirtualOccluder {
  enum class Shape { kSphere, kBox };
  Shape shape = Shape::kSphere;
  glm::dvec2 position_w{0.0};               // where it stands on the ground, W metres
  double radius_m = 0.035;                  // sphere: radius; its centre is at z = radius_m
  glm::dvec3 box_size_m{0.05, 0.05, 0.05};  // box: full edge lengths along its own x, y, z; bottom face on the ground
  double box_yaw_deg = 0.0;                 // box: rotation about +Z (counter-clockwise seen from above)
  glm::dvec3 albedo{0.8, 0.8, 0.8};         // Lambertian, for renderWithOccluders
};

// Nearest hit distance t > 0 along origin + t * dir (dir unit) with the occluder's surface, and the outward unit normal there.
std::optional<double> intersectOccluder(const VirtualOccluder& occluder, const glm::dvec3& origin, const glm::dvec3& dir,
                                        glm::dvec3* normal_out = nullptr);

// The smallest sphere around the occluder (sphere: itself; box: through its
// corners). Seen from a point at distance D > radius_m from center_w, every
// direction that can hit the occluder lies in a cone of half-angle
// asin(radius_m / D) around the direction to center_w.
struct OccluderBound {
  glm::dvec3 center_w{0.0};
  double radius_m = 0.0;
};
OccluderBound occluderBound(const VirtualOccluder& occluder);

// A box's own frame: origin at its centre, x and y along its yawed edges, z up.
// Points and directions go between W and that frame with these.
glm::dvec3 boxCenterWorld(const VirtualOccluder& box);
glm::dvec3 boxLocalFromWorldDirection(const VirtualOccluder& box, const glm::dvec3& dir_w);
glm::dvec3 boxWorldFromLocalDirection(const VirtualOccluder& box, const glm::dvec3& dir_local);

}  // namespace probelight::sim
