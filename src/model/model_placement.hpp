// Where a model stands on the tag: its origin at a point of the ground
// (the world frame is the tag's: Z up, the ground at z = 0), turned about
// +Z and scaled, and lifted so that its lowest point rests on the ground
// (a model's origin may be anywhere: at its feet, its centre, or off to one
// side). Pure maths: the renderer, the shadow pass and the simulator all
// place a model with this one transform.
#pragma once

#include <glm/glm.hpp>

#include "model/mesh_model.hpp"

namespace probelight::model {

struct ModelPlacement {
  glm::dvec2 position_m{0.0};  // where the model's origin stands, in the tag frame
  double yaw_rad = 0.0;        // turned about +Z (counter-clockwise seen from above)
  double scale = 1.0;          // > 0; glTF's unit is the metre
};

// world_from_model = T(position, lift) * Rz(yaw) * S(scale): lift is
// -scale * model.min_m.z, which puts the lowest vertex at z = 0 (a turn
// about Z and a uniform scale keep the lowest vertex the lowest).
glm::dmat4 worldFromModel(const MeshModel& model, const ModelPlacement& placement);

// A sphere around every vertex once placed: centred on the placed bounding
// box's centre, with the radius to the farthest vertex (so it holds them
// all exactly, and is at most the box's half diagonal). What the shadow
// maps' frustum and the ground region are fitted to.
struct BoundingSphere {
  glm::dvec3 centre_w{0.0};
  double radius_m = 0.0;
};
BoundingSphere placedBoundingSphere(const MeshModel& model, const glm::dmat4& world_from_model);

}  // namespace probelight::model
