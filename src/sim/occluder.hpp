// Virtual objects standing on the ground, for the truth of the shadows they
// cast (World::groundShadow) and for frames that show them
// (World::renderWithOccluders). Plain geometry: no lighting here.
#pragma once

#include <limits>
#include <memory>
#include <optional>

#include <glm/glm.hpp>

#include "model/mesh_model.hpp"
#include "sim/triangle_bvh.hpp"

namespace probelight::sim {

// A virtual object standing on the ground (z = 0) in W, for the shadow truth.
struct VirtualOccluder {
  // kMesh: a user's model (meshOccluder), traced triangle by triangle and
  // shaded by path tracing with its own glTF materials.
  enum class Shape { kSphere, kBox, kMesh };
  Shape shape = Shape::kSphere;
  glm::dvec2 position_w{0.0};               // where it stands on the ground, W metres
  double radius_m = 0.035;                  // sphere: radius; its centre is at z = radius_m
  glm::dvec3 box_size_m{0.05, 0.05, 0.05};  // box: full edge lengths along its own x, y, z; bottom face on the ground
  double box_yaw_deg = 0.0;                 // box: rotation about +Z (counter-clockwise seen from above)
  glm::dvec3 albedo{0.8, 0.8, 0.8};         // Lambertian, for renderWithOccluders (not kMesh: its materials)
  // kMesh: the model (for its materials and textures) and its triangles
  // placed in W. position_w is unused: the triangles are where they are.
  std::shared_ptr<const model::MeshModel> model;
  std::shared_ptr<const TriangleScene> triangles;
  // kMesh: some material is MASK, so a shadow ray must look at each hit's
  // texel (meshOccluder sets it).
  bool has_mask_material = false;
  // kMesh, in renderWithOccluders: paths per shaded camera sample (an edge
  // pixel's sub-samples share them), and how many times a path may bounce
  // off the model itself before it ends (the interreflection the truth
  // holds; 0: direct light from the sky and the floor only).
  int path_samples = 64;
  int max_bounces = 4;
  // kMesh, in renderWithOccluders: light the model with what an 8-bit camera
  // can know through the ball rather than the full HDR sky: each sky
  // direction scaled by the clip of the ball pixel that shows it in this
  // frame (a lamp smaller than a pixel clips the whole pixel; directions
  // behind the ball clipped one by one, as World::irradiance's `clipped`),
  // and the floor clipped as the camera clips it. The frame around it is
  // unchanged.
  bool clipped_lighting = false;
};

// A model placed in W by world_from_model (metres, Z up, as the kiosk
// places it) as an occluder: its triangles in the simulator's own BVH.
VirtualOccluder meshOccluder(std::shared_ptr<const model::MeshModel> model, const glm::dmat4& world_from_model);

// kMesh: the closest hit in (t_min, t_max) of a surface that is there: a
// MASK material's texels under its cutoff are holes the ray passes through
// (as the kiosk discards them). BLEND surfaces count as opaque.
std::optional<TriangleHit> intersectMesh(const VirtualOccluder& mesh, const glm::dvec3& origin, const glm::dvec3& dir,
                                         double t_max);

// Whether the ray from origin along dir (unit) meets the occluder's surface
// at all, nearer than t_max: a shadow ray. For a mesh without MASK
// materials the BVH stops at the first triangle it finds (any hit), where
// intersectMesh must go on to the closest.
bool occluderBlocks(const VirtualOccluder& occluder, const glm::dvec3& origin, const glm::dvec3& dir,
                    double t_max = std::numeric_limits<double>::infinity());

// Nearest hit distance t > 0 along origin + t * dir (dir unit) with the occluder's surface, and the outward unit normal
// there (kMesh: the shading normal, turned towards the ray's origin).
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
