// Models made from a few numbers rather than a file: surfaces of
// revolution (a sphere, a bowl, a vase: any profile turned about +Z) and a
// box, as MeshModels with normals and UVs. The simulator's truth, the
// accuracy checks and the bench need shapes whose geometry is known exactly
// (a sphere's normals, a bowl's inside) at any triangle count; the loader
// gives only what files happen to hold.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "model/mesh_model.hpp"

namespace probelight::model {

// One smooth run of a profile: points (r, z) in metres, r >= 0 the distance
// from the axis, in order along the surface. The surface's outside is on
// the right of the run's direction, with r to the right and z up: a run up
// the outside of a sphere, or down the inside of a bowl. Normals are smooth
// along a run; where two runs meet there is a crease.
struct ProfileRun {
  std::vector<glm::dvec2> points_rz;
  // The surface's unit normal (r, z) at each point, where the caller knows
  // it (a sphere's is radial); empty: from the profile's tangent, which at
  // a run's ends is only the end segment's.
  std::vector<glm::dvec2> normals_rz;
};

// The runs turned about +Z in `segments` steps (>= 3), wound counter-
// clockwise seen from the outside, with UVs (u around, v along the
// profile) and one material. Triangles that would collapse onto the axis
// are left out. Empty for a profile with fewer than two points in a run.
MeshModel surfaceOfRevolution(const std::vector<ProfileRun>& runs, int segments, const Material& material);

// A sphere of radius_m with `rings` (>= 2) steps from pole to pole and
// 2 * rings around: 4 rings^2 - 4 rings triangles. Its centre at the origin.
MeshModel sphereModel(double radius_m, int rings, const Material& material);

// A hemispherical bowl open at the top: outer radius outer_radius_m, wall
// wall_m thick, a flat rim; `rings` steps over each quarter circle. The
// rim at z = 0, the bottom at -outer_radius_m.
MeshModel bowlModel(double outer_radius_m, double wall_m, int rings, const Material& material);

// A box of size_m (edges along x, y, z) centred at the origin: 12
// triangles, flat normals, each face's UVs over [0, 1]^2.
MeshModel boxModel(const glm::dvec3& size_m, const Material& material);

}  // namespace probelight::model
