// A user's model as the simulator's ray tracer sees it: every triangle of a
// model::MeshModel placed in the world (Z up, metres) in double precision,
// with what shading needs at a hit (normals, UVs, vertex colours, material),
// and a bounding volume hierarchy so a frame's half a million rays do not
// each test every triangle. The oracle's own code: nothing here comes from
// src/ibl, which it checks.
//
// The ray-triangle test is the watertight one of Woop, Benthin and Wald
// (JCGT 2013): the ray's frame is sheared so the ray is the +z axis, and the
// three edge functions are evaluated on the sheared vertices. Two triangles
// that share an edge evaluate that edge's function from the same two
// vertices with the signs swapped, exactly, so a ray through the edge (or a
// shared vertex) hits at least one of them: no cracks, in any precision.
// The box tests are made conservative for the same reason (Ize 2013).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "model/mesh_model.hpp"

namespace probelight::sim {

// An axis-aligned box in the world frame, metres.
struct WorldBounds {
  glm::dvec3 min_w{0.0}, max_w{0.0};
  bool empty() const { return !(min_w.x <= max_w.x && min_w.y <= max_w.y && min_w.z <= max_w.z); }
};

// The closest hit of a ray, and the surface there.
struct TriangleHit {
  double t = 0.0;              // along origin + t * dir
  std::size_t triangle = 0;    // TriangleScene's index: the model's triangles in primitive order
  int primitive = 0;           // into MeshModel::primitives
  int material = -1;           // the primitive's: into MeshModel::materials, -1 glTF's default
  // Weights of the triangle's vertices 0, 1, 2 at the hit (sum 1, each >= 0
  // up to rounding): the hit point is their mix of the vertices.
  glm::dvec3 barycentric{1.0, 0.0, 0.0};
  // Unit, (p1 - p0) x (p2 - p0): the side glTF calls front (counter-clockwise
  // seen from it; turned over where world_from_model mirrors).
  glm::dvec3 geometric_normal{0.0, 0.0, 1.0};
  // Unit; the vertex normals mixed (the geometric normal where the primitive
  // has none). Not flipped towards the ray: back_face says which side it hit.
  glm::dvec3 shading_normal{0.0, 0.0, 1.0};
  glm::dvec2 uv0{0.0}, uv1{0.0};  // (0, 0) where the primitive has no such set
  glm::dvec4 color{1.0};          // COLOR_0 mixed, linear RGBA; 1 where the primitive has none
  bool back_face = false;         // the ray came from behind the geometric normal
};

class TriangleScene {
 public:
  // Every triangle of `model` moved by world_from_model (any affine map;
  // one that mirrors, det < 0, has its geometric normals turned over so that
  // they still point to the side glTF calls front). Normals go
  // through the inverse transpose. Triangles of zero area (to rounding) are
  // kept for their index but never hit (isDegenerate).
  TriangleScene(const model::MeshModel& model, const glm::dmat4& world_from_model);

  // The closest hit with t_min() < t < t_max along origin + t * dir. dir
  // need not be unit length, but t counts in lengths of dir, and t_min()
  // is in metres only for a unit dir.
  std::optional<TriangleHit> intersect(const glm::dvec3& origin, const glm::dvec3& dir, double t_max) const;
  // Whether anything lies in t_min() < t < t_max: a shadow ray, which stops
  // at the first hit it finds.
  bool occluded(const glm::dvec3& origin, const glm::dvec3& dir, double t_max) const;

  // The same as intersect(), testing every triangle in turn: what the BVH is
  // checked against. Too slow for anything else.
  std::optional<TriangleHit> intersectEveryTriangle(const glm::dvec3& origin, const glm::dvec3& dir,
                                                    double t_max) const;

  // Hits closer than this are the surface a ray starts on: 1e-9 of the
  // scene's size (its bounds' diagonal, or its largest coordinate when the
  // scene stands far from the origin). A hit point computed in double is off
  // its plane by ~1e-16 of its coordinates, so a ray spawned there and
  // leaving at more than ~1e-6 rad from the plane clears it; 1e-9 of a 1 m
  // model is 1 nm, far below any feature a model has.
  double t_min() const { return t_min_; }

  WorldBounds bounds() const { return bounds_; }
  std::size_t triangleCount() const { return triangles_.size(); }
  std::size_t degenerateCount() const { return degenerate_count_; }
  bool isDegenerate(std::size_t triangle) const { return triangles_[triangle].degenerate; }
  // Vertices 0, 1, 2 of a triangle, world metres, in the order glTF winds them.
  std::array<glm::dvec3, 3> vertices(std::size_t triangle) const { return triangles_[triangle].position_w; }
  // BVH nodes, and the depth of its deepest leaf (for tests of the build).
  std::size_t nodeCount() const { return nodes_.size(); }
  int depth() const { return depth_; }

 private:
  struct Triangle {
    std::array<glm::dvec3, 3> position_w;
    std::array<glm::dvec3, 3> normal_w;  // unit
    std::array<glm::dvec2, 3> uv0, uv1;
    std::array<glm::dvec4, 3> color;
    glm::dvec3 geometric_normal{0.0};  // unit, as wound
    int primitive = 0, material = -1;
    bool degenerate = false;
  };
  // Leaf: count > 0 triangles from `first` of order_. Inner: count == 0, its
  // children are nodes_[first] and nodes_[first + 1].
  struct Node {
    WorldBounds box;
    std::uint32_t first = 0, count = 0;
  };
  class RayTest;  // the per-ray part of the watertight test, in the .cpp

  void build();
  template <bool kAnyHit>
  bool traverse(const RayTest& ray, double t_max, std::size_t* hit_triangle, double* hit_t, glm::dvec3* hit_b) const;
  TriangleHit surfaceHit(const glm::dvec3& dir, std::size_t triangle, double t, const glm::dvec3& barycentric) const;

  std::vector<Triangle> triangles_;
  std::vector<std::uint32_t> order_;  // the BVH's leaves index triangles through this
  std::vector<Node> nodes_;
  WorldBounds bounds_;
  double t_min_ = 1e-9;
  std::size_t degenerate_count_ = 0;
  int depth_ = 0;
};

}  // namespace probelight::sim
