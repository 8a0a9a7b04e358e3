#include "sim/triangle_bvh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace probelight::sim {
namespace {

constexpr std::uint32_t kMaxLeafTriangles = 4;
constexpr int kSahBins = 16;
// Below this depth nodes split where the binned SAH says; deeper ones split
// at the median triangle, which halves them, so no leaf lies deeper than
// kSahDepth + log2(triangles / kMaxLeafTriangles) (< 80 for four billion
// triangles) and a traversal stack of kStackSize never overflows, whatever
// the model (a long run of tiny triangles beside a huge one makes the SAH
// peel them off one by one).
constexpr int kSahDepth = 48;
constexpr int kStackSize = 96;
// What the degenerate test calls parallel edges: sin of the angle between
// them. A triangle that thin has an area of 1e-14 of its edges' product:
// nothing any ray should find, and what the edge functions cannot resolve.
constexpr double kDegenerateSine = 1e-14;
// Scale of the self-hit guard, t_min(): see the header.
constexpr double kRelativeTMin = 1e-9;

// Ize, "Robust BVH ray traversal" (JCGT 2013): the exit distance of a slab
// test grown by 2 gamma(3) covers the rounding of the three operations
// behind each slab distance, so a box never loses a ray that hits what it
// holds (which would be a crack at node boundaries, not triangle edges).
constexpr double kBoxExitGrowth = 1.0 + 2.0 * (3.0 * 0.5 * std::numeric_limits<double>::epsilon()) /
                                            (1.0 - 3.0 * 0.5 * std::numeric_limits<double>::epsilon());

void grow(WorldBounds& box, const glm::dvec3& p) {
  box.min_w = glm::min(box.min_w, p);
  box.max_w = glm::max(box.max_w, p);
}
void grow(WorldBounds& box, const WorldBounds& other) {
  box.min_w = glm::min(box.min_w, other.min_w);
  box.max_w = glm::max(box.max_w, other.max_w);
}
WorldBounds emptyBounds() {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  return {glm::dvec3(kInf), glm::dvec3(-kInf)};
}
double surfaceArea(const WorldBounds& box) {
  if (box.empty()) return 0.0;
  const glm::dvec3 d = box.max_w - box.min_w;
  return 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
}

}  // namespace

// The ray's part of Woop et al.'s test, computed once per ray: the axis the
// ray runs most along becomes z, and the shear that makes the ray the +z
// axis. Swapping x and y where the ray runs along -z keeps the winding, so
// the edge functions' signs mean the same for every ray.
class TriangleScene::RayTest {
 public:
  RayTest(const glm::dvec3& origin, const glm::dvec3& dir) : origin_(origin) {
    const glm::dvec3 a = glm::abs(dir);
    kz_ = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    kx_ = (kz_ + 1) % 3;
    ky_ = (kx_ + 1) % 3;
    if (dir[kz_] < 0.0) std::swap(kx_, ky_);
    shear_x_ = dir[kx_] / dir[kz_];
    shear_y_ = dir[ky_] / dir[kz_];
    shear_z_ = 1.0 / dir[kz_];
    // A zero (or denormal) component would give 0 * inf = NaN in the slab
    // test for an origin on the slab's plane; 1e300 keeps every product a
    // number and treats that origin as inside the slab, which is conservative.
    for (int i = 0; i < 3; ++i) inv_dir_[i] = 1.0 / (std::abs(dir[i]) > 1e-300 ? dir[i] : 1e-300);
  }

  bool valid() const { return std::isfinite(shear_x_) && std::isfinite(shear_y_) && std::isfinite(shear_z_); }

  // t and the weights of vertices 0, 1, 2 where the ray crosses the
  // triangle with t_min < t < t_max; false on a miss.
  bool hit(const std::array<glm::dvec3, 3>& p, double t_min, double t_max, double& t, glm::dvec3& weights) const {
    const glm::dvec3 a = p[0] - origin_, b = p[1] - origin_, c = p[2] - origin_;
    const double ax = a[kx_] - shear_x_ * a[kz_], ay = a[ky_] - shear_y_ * a[kz_];
    const double bx = b[kx_] - shear_x_ * b[kz_], by = b[ky_] - shear_y_ * b[kz_];
    const double cx = c[kx_] - shear_x_ * c[kz_], cy = c[ky_] - shear_y_ * c[kz_];
    // Twice the signed areas the ray's point makes with each edge: the edge
    // opposite vertex 0, 1 and 2. Zero counts as inside, so a ray along a
    // shared edge hits both triangles rather than neither.
    const double u = cx * by - cy * bx;
    const double v = ax * cy - ay * cx;
    const double w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    const double det = u + v + w;
    if (det == 0.0) return false;  // seen edge-on: no area to cross
    const double t_scaled = u * shear_z_ * a[kz_] + v * shear_z_ * b[kz_] + w * shear_z_ * c[kz_];
    const double t_hit = t_scaled / det;
    if (!(t_hit > t_min && t_hit < t_max)) return false;  // NaN fails too
    t = t_hit;
    weights = glm::dvec3(u, v, w) / det;
    return true;
  }

  // Where the ray enters the box, or +inf where it misses it or the box
  // lies outside (t_min, t_max).
  double boxEntry(const WorldBounds& box, double t_min, double t_max) const {
    double t_near = t_min, t_far = t_max;
    for (int i = 0; i < 3; ++i) {
      double t0 = (box.min_w[i] - origin_[i]) * inv_dir_[i];
      double t1 = (box.max_w[i] - origin_[i]) * inv_dir_[i];
      if (t0 > t1) std::swap(t0, t1);
      t_near = std::max(t_near, t0);
      t_far = std::min(t_far, t1 * kBoxExitGrowth);
    }
    return t_near <= t_far ? t_near : std::numeric_limits<double>::infinity();
  }

 private:
  glm::dvec3 origin_;
  glm::dvec3 inv_dir_{0.0};
  int kx_ = 0, ky_ = 1, kz_ = 2;
  double shear_x_ = 0.0, shear_y_ = 0.0, shear_z_ = 0.0;
};

TriangleScene::TriangleScene(const model::MeshModel& model, const glm::dmat4& world_from_model) {
  const glm::dmat3 linear(world_from_model);
  const glm::dmat3 normal_from_model = glm::transpose(glm::inverse(linear));
  const double front_sign = glm::determinant(linear) < 0.0 ? -1.0 : 1.0;
  bounds_ = emptyBounds();
  triangles_.reserve(model.triangleCount());
  for (std::size_t pi = 0; pi < model.primitives.size(); ++pi) {
    const model::Primitive& primitive = model.primitives[pi];
    const std::size_t vertex_count = primitive.positions_m.size();
    for (std::size_t first = 0; first + 2 < primitive.indices.size(); first += 3) {
      Triangle tri;
      // glm leaves vectors uninitialised: a primitive without UVs gets 0.
      tri.position_w.fill(glm::dvec3(0.0));
      tri.normal_w.fill(glm::dvec3(0.0));
      tri.uv0.fill(glm::dvec2(0.0));
      tri.uv1.fill(glm::dvec2(0.0));
      tri.color.fill(glm::dvec4(1.0));
      tri.primitive = static_cast<int>(pi);
      tri.material = primitive.material;
      bool indices_ok = true;
      for (int k = 0; k < 3; ++k) {
        const std::size_t i = primitive.indices[first + static_cast<std::size_t>(k)];
        // The loader checks every index; one out of range here still gives a
        // triangle (so indices keep their meaning), a degenerate one.
        if (i >= vertex_count) {
          indices_ok = false;
          continue;
        }
        tri.position_w[k] = glm::dvec3(world_from_model * glm::dvec4(glm::dvec3(primitive.positions_m[i]), 1.0));
        if (i < primitive.normals.size()) tri.normal_w[k] = normal_from_model * glm::dvec3(primitive.normals[i]);
        if (i < primitive.uv0.size()) tri.uv0[k] = glm::dvec2(primitive.uv0[i]);
        if (i < primitive.uv1.size()) tri.uv1[k] = glm::dvec2(primitive.uv1[i]);
        if (i < primitive.colors.size()) tri.color[k] = glm::dvec4(primitive.colors[i]);
      }
      const glm::dvec3 e1 = tri.position_w[1] - tri.position_w[0], e2 = tri.position_w[2] - tri.position_w[0];
      const glm::dvec3 cross = glm::cross(e1, e2);
      const double cross_length = glm::length(cross);
      tri.degenerate = !indices_ok || !std::isfinite(cross_length) ||
                       !(cross_length > kDegenerateSine * glm::length(e1) * glm::length(e2));
      if (!tri.degenerate) {
        tri.geometric_normal = front_sign * cross / cross_length;
        for (int k = 0; k < 3; ++k) {
          // A vertex without a normal, or one the transform crushed, shades flat.
          const double n = glm::length(tri.normal_w[k]);
          tri.normal_w[k] = n > 0.0 && std::isfinite(n) ? tri.normal_w[k] / n : tri.geometric_normal;
        }
        for (const glm::dvec3& p : tri.position_w) grow(bounds_, p);
      } else {
        ++degenerate_count_;
      }
      triangles_.push_back(tri);
    }
  }
  if (bounds_.empty()) bounds_ = WorldBounds{};
  const double scale = std::max(glm::length(bounds_.max_w - bounds_.min_w),
                                std::max(glm::length(bounds_.min_w), glm::length(bounds_.max_w)));
  t_min_ = kRelativeTMin * (scale > 0.0 ? scale : 1.0);
  build();
}

void TriangleScene::build() {
  std::vector<WorldBounds> boxes(triangles_.size());
  std::vector<glm::dvec3> centroids(triangles_.size());
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    if (triangles_[i].degenerate) continue;
    boxes[i] = emptyBounds();
    for (const glm::dvec3& p : triangles_[i].position_w) grow(boxes[i], p);
    centroids[i] = 0.5 * (boxes[i].min_w + boxes[i].max_w);
    order_.push_back(static_cast<std::uint32_t>(i));
  }
  if (order_.empty()) return;
  nodes_.reserve(2 * order_.size() / kMaxLeafTriangles + 1);
  nodes_.push_back({});

  struct Task {
    std::uint32_t node, begin, end;
    int depth;
  };
  std::vector<Task> tasks{{0, 0, static_cast<std::uint32_t>(order_.size()), 1}};
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    WorldBounds box = emptyBounds(), centroid_box = emptyBounds();
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      grow(box, boxes[order_[i]]);
      grow(centroid_box, centroids[order_[i]]);
    }
    nodes_[task.node].box = box;
    const std::uint32_t count = task.end - task.begin;
    if (count <= kMaxLeafTriangles) {
      nodes_[task.node].first = task.begin;
      nodes_[task.node].count = count;
      depth_ = std::max(depth_, task.depth);
      continue;
    }

    // Binned SAH (Wald 2007): centroids into kSahBins slabs along each axis,
    // and the plane between bins that minimises area x count on both sides.
    // A node above kMaxLeafTriangles always splits, so the leaf's own cost
    // never enters.
    int best_axis = -1, best_split = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    const glm::dvec3 extent = centroid_box.max_w - centroid_box.min_w;
    auto binOf = [&](std::uint32_t triangle, int axis) {
      const double f = (centroids[triangle][axis] - centroid_box.min_w[axis]) * (kSahBins / extent[axis]);
      return std::min(kSahBins - 1, static_cast<int>(f));
    };
    if (task.depth < kSahDepth) {
      for (int axis = 0; axis < 3; ++axis) {
        if (!(extent[axis] > 0.0)) continue;
        std::array<WorldBounds, kSahBins> bin_box;
        std::array<std::uint32_t, kSahBins> bin_count{};
        bin_box.fill(emptyBounds());
        for (std::uint32_t i = task.begin; i < task.end; ++i) {
          const int bin = binOf(order_[i], axis);
          grow(bin_box[bin], boxes[order_[i]]);
          ++bin_count[bin];
        }
        std::array<double, kSahBins> left_cost{};
        WorldBounds left = emptyBounds();
        std::uint32_t left_count = 0;
        for (int split = 1; split < kSahBins; ++split) {
          grow(left, bin_box[split - 1]);
          left_count += bin_count[split - 1];
          left_cost[split] = surfaceArea(left) * left_count;
        }
        WorldBounds right = emptyBounds();
        std::uint32_t right_count = 0;
        for (int split = kSahBins - 1; split >= 1; --split) {
          grow(right, bin_box[split]);
          right_count += bin_count[split];
          if (right_count == 0 || right_count == count) continue;
          const double cost = left_cost[split] + surfaceArea(right) * right_count;
          if (cost < best_cost) {
            best_cost = cost;
            best_axis = axis;
            best_split = split;
          }
        }
      }
    }
    std::uint32_t middle = task.begin;
    if (best_axis >= 0) {
      auto* split_at = std::partition(order_.data() + task.begin, order_.data() + task.end,
                                      [&](std::uint32_t t) { return binOf(t, best_axis) < best_split; });
      middle = static_cast<std::uint32_t>(split_at - order_.data());
    }
    if (middle == task.begin || middle == task.end) {
      // All centroids in one point, or deep enough to stop trusting the SAH:
      // the median along the longest extent.
      const int axis = extent.x >= extent.y ? (extent.x >= extent.z ? 0 : 2) : (extent.y >= extent.z ? 1 : 2);
      middle = task.begin + count / 2;
      std::nth_element(order_.begin() + task.begin, order_.begin() + middle, order_.begin() + task.end,
                       [&](std::uint32_t l, std::uint32_t r) { return centroids[l][axis] < centroids[r][axis]; });
    }
    const auto children = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({});
    nodes_.push_back({});
    nodes_[task.node].first = children;
    nodes_[task.node].count = 0;
    tasks.push_back({children, task.begin, middle, task.depth + 1});
    tasks.push_back({children + 1, middle, task.end, task.depth + 1});
  }
}

template <bool kAnyHit>
bool TriangleScene::traverse(const RayTest& ray, double t_max, std::size_t* hit_triangle, double* hit_t,
                             glm::dvec3* hit_b) const {
  if (nodes_.empty() || !ray.valid()) return false;
  double best_t = t_max;
  bool found = false;
  std::array<std::uint32_t, kStackSize> stack;
  int top = 0;
  std::uint32_t node = 0;
  if (!std::isfinite(ray.boxEntry(nodes_[0].box, t_min_, best_t))) return false;
  while (true) {
    const Node& n = nodes_[node];
    if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        double t;
        glm::dvec3 b;
        if (ray.hit(triangles_[order_[i]].position_w, t_min_, best_t, t, b)) {
          found = true;
          best_t = t;
          *hit_triangle = order_[i];
          *hit_t = t;
          *hit_b = b;
          if constexpr (kAnyHit) return true;
        }
      }
    } else {
      // Nearest child first, so the closest hit shrinks best_t early and
      // the farther child is often culled when it comes off the stack.
      std::uint32_t near_child = n.first, far_child = n.first + 1;
      double near_t = ray.boxEntry(nodes_[near_child].box, t_min_, best_t);
      double far_t = ray.boxEntry(nodes_[far_child].box, t_min_, best_t);
      if (far_t < near_t) {
        std::swap(near_child, far_child);
        std::swap(near_t, far_t);
      }
      if (std::isfinite(near_t)) {
        if (std::isfinite(far_t)) stack[top++] = far_child;  // build() bounds the depth below kStackSize
        node = near_child;
        continue;
      }
    }
    // Pop the next node that may still hold something closer than best_t.
    bool next = false;
    while (top > 0) {
      node = stack[--top];
      if (std::isfinite(ray.boxEntry(nodes_[node].box, t_min_, best_t))) {
        next = true;
        break;
      }
    }
    if (!next) break;
  }
  return found;
}

TriangleHit TriangleScene::surfaceHit(const glm::dvec3& dir, std::size_t triangle, double t,
                                      const glm::dvec3& barycentric) const {
  const Triangle& tri = triangles_[triangle];
  TriangleHit hit;
  hit.t = t;
  hit.triangle = triangle;
  hit.primitive = tri.primitive;
  hit.material = tri.material;
  hit.barycentric = barycentric;
  hit.geometric_normal = tri.geometric_normal;
  const glm::dvec3 normal =
      barycentric.x * tri.normal_w[0] + barycentric.y * tri.normal_w[1] + barycentric.z * tri.normal_w[2];
  const double length = glm::length(normal);
  // Opposed vertex normals can cancel: the geometric normal is the only
  // direction left that means anything there.
  hit.shading_normal = length > 1e-12 ? normal / length : tri.geometric_normal;
  hit.uv0 = barycentric.x * tri.uv0[0] + barycentric.y * tri.uv0[1] + barycentric.z * tri.uv0[2];
  hit.uv1 = barycentric.x * tri.uv1[0] + barycentric.y * tri.uv1[1] + barycentric.z * tri.uv1[2];
  hit.color = barycentric.x * tri.color[0] + barycentric.y * tri.color[1] + barycentric.z * tri.color[2];
  hit.back_face = glm::dot(tri.geometric_normal, dir) > 0.0;
  return hit;
}

std::optional<TriangleHit> TriangleScene::intersect(const glm::dvec3& origin, const glm::dvec3& dir,
                                                    double t_max) const {
  const RayTest ray(origin, dir);
  std::size_t triangle = 0;
  double t = 0.0;
  glm::dvec3 b(0.0);
  if (!traverse<false>(ray, t_max, &triangle, &t, &b)) return std::nullopt;
  return surfaceHit(dir, triangle, t, b);
}

bool TriangleScene::occluded(const glm::dvec3& origin, const glm::dvec3& dir, double t_max) const {
  const RayTest ray(origin, dir);
  std::size_t triangle = 0;
  double t = 0.0;
  glm::dvec3 b(0.0);
  return traverse<true>(ray, t_max, &triangle, &t, &b);
}

std::optional<TriangleHit> TriangleScene::intersectEveryTriangle(const glm::dvec3& origin, const glm::dvec3& dir,
                                                                 double t_max) const {
  const RayTest ray(origin, dir);
  if (!ray.valid()) return std::nullopt;
  double best_t = t_max;
  std::optional<std::size_t> best;
  glm::dvec3 best_b(0.0);
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    if (triangles_[i].degenerate) continue;
    double t;
    glm::dvec3 b;
    if (ray.hit(triangles_[i].position_w, t_min_, best_t, t, b)) {
      best_t = t;
      best = i;
      best_b = b;
    }
  }
  if (!best) return std::nullopt;
  return surfaceHit(dir, *best, best_t, best_b);
}

}  // namespace probelight::sim
