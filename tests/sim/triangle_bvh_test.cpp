// The simulator's triangle ray tracer (sim/triangle_bvh.hpp): its BVH
// against testing every triangle, and against an independent Möller–Trumbore
// test, on a real corpus model; exact distances on a placed box against the
// analytic box; no ray slipping through a closed mesh; shadow rays agreeing
// with closest hits; degenerate triangles; the attributes a hit carries.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/math_constants.hpp"
#include "model/gltf_loader.hpp"
#include "model/model_placement.hpp"
#include "sim/triangle_bvh.hpp"

namespace probelight::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const std::string kCorpus = "/usr/share/assimp/models/glTF2/";

// Loaded once for the whole binary: the engine takes a while to read.
const model::MeshModel& corpusModel(const std::string& relative) {
  static std::map<std::string, model::MeshModel> loaded;
  auto it = loaded.find(relative);
  if (it == loaded.end()) {
    model::MeshModel m;
    std::string error;
    EXPECT_TRUE(model::loadGltfModel(kCorpus + relative, {}, m, error))
        << error << " (install Debian's assimp-testmodels: scripts/install-deps.sh)";
    it = loaded.emplace(relative, std::move(m)).first;
  }
  return it->second;
}

const char* kEngine = "2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
const char* kBox = "BoxTextured-glTF/BoxTextured.gltf";

// A placement that makes the model `size_m` across its largest extent.
model::ModelPlacement placementOfSize(const model::MeshModel& m, double size_m, glm::dvec2 position_m, double yaw_rad) {
  const glm::dvec3 extent = glm::dvec3(m.max_m) - glm::dvec3(m.min_m);
  model::ModelPlacement placement;
  placement.position_m = position_m;
  placement.yaw_rad = yaw_rad;
  placement.scale = size_m / std::max(extent.x, std::max(extent.y, extent.z));
  return placement;
}

glm::dvec3 uniformSphere(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double z = 2.0 * u(rng) - 1.0, phi = 2.0 * kPi * u(rng);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

glm::dvec3 pointIn(const WorldBounds& box, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  return box.min_w + glm::dvec3(u(rng), u(rng), u(rng)) * (box.max_w - box.min_w);
}

// The textbook Möller–Trumbore test, written here and nowhere else: a second
// opinion on the distance the scene's watertight test finds.
std::optional<double> mollerTrumbore(const glm::dvec3& o, const glm::dvec3& d, const std::array<glm::dvec3, 3>& p) {
  const glm::dvec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
  const glm::dvec3 q = glm::cross(d, e2);
  const double det = glm::dot(e1, q);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const glm::dvec3 s = o - p[0];
  const double u = glm::dot(s, q) / det;
  const glm::dvec3 r = glm::cross(s, e1);
  const double v = glm::dot(d, r) / det;
  // A hit the watertight test finds on an edge can fall just outside here.
  constexpr double kSlack = 1e-9;
  if (u < -kSlack || v < -kSlack || u + v > 1.0 + kSlack) return std::nullopt;
  return glm::dot(e2, r) / det;
}

bool finite(const TriangleHit& hit) {
  auto ok = [](auto v) {
    for (int i = 0; i < v.length(); ++i)
      if (!std::isfinite(v[i])) return false;
    return true;
  };
  return std::isfinite(hit.t) && ok(hit.barycentric) && ok(hit.geometric_normal) && ok(hit.shading_normal) &&
         ok(hit.uv0) && ok(hit.uv1) && ok(hit.color);
}

// Rays from outside a scene's bounding sphere aimed at points of its box
// (most hit, many graze), and rays from inside its box in any direction.
std::vector<std::pair<glm::dvec3, glm::dvec3>> raysAround(const TriangleScene& scene, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const WorldBounds box = scene.bounds();
  const glm::dvec3 centre = 0.5 * (box.min_w + box.max_w);
  const double radius = 0.5 * glm::length(box.max_w - box.min_w);
  std::vector<std::pair<glm::dvec3, glm::dvec3>> rays;
  for (int i = 0; i < count; ++i) {
    if (i % 2 == 0) {
      const glm::dvec3 origin = centre + 1.5 * radius * uniformSphere(rng);
      rays.emplace_back(origin, glm::normalize(pointIn(box, rng) - origin));
    } else {
      rays.emplace_back(pointIn(box, rng), uniformSphere(rng));
    }
  }
  return rays;
}

// The BVH finds what testing every triangle finds. Both run the same
// per-triangle test, so the distances are the same double unless a box test
// culled a node by the rounding of its entry distance against a hit a few
// ulps closer: hence 1e-12 relative, and another triangle accepted only at
// the same distance (coplanar duplicates and shared edges tie). The
// independent Möller–Trumbore distance agrees to 1e-9 relative: both are
// double, and a grazing ray loses digits in either.
void expectBvhMatchesEveryTriangle(const TriangleScene& scene, int ray_count, std::uint64_t seed,
                                   double min_hit_fraction) {
  int hits = 0;
  for (const auto& [origin, dir] : raysAround(scene, ray_count, seed)) {
    const std::optional<TriangleHit> bvh = scene.intersect(origin, dir, kInf);
    const std::optional<TriangleHit> every = scene.intersectEveryTriangle(origin, dir, kInf);
    ASSERT_EQ(bvh.has_value(), every.has_value()) << "ray from (" << origin.x << ", " << origin.y << ", " << origin.z
                                                  << ") along (" << dir.x << ", " << dir.y << ", " << dir.z << ")";
    if (!bvh) continue;
    ++hits;
    ASSERT_TRUE(finite(*bvh));
    // The same distance; another triangle only at that distance (a tie).
    EXPECT_NEAR(bvh->t, every->t, 1e-12 * every->t) << "triangles " << bvh->triangle << ", " << every->triangle;
    const std::optional<double> mt = mollerTrumbore(origin, dir, scene.vertices(every->triangle));
    ASSERT_TRUE(mt.has_value());
    EXPECT_NEAR(*mt, every->t, 1e-9 * every->t);
    EXPECT_NEAR(glm::length(bvh->geometric_normal), 1.0, 1e-12);
    EXPECT_NEAR(glm::length(bvh->shading_normal), 1.0, 1e-12);
    EXPECT_NEAR(bvh->barycentric.x + bvh->barycentric.y + bvh->barycentric.z, 1.0, 1e-12);
    EXPECT_EQ(bvh->back_face, glm::dot(bvh->geometric_normal, dir) > 0.0);
  }
  EXPECT_GE(hits, min_hit_fraction * ray_count) << "the rays must mostly hit for the test to mean anything";
}

TEST(TriangleBvh, EngineClosestHitIsWhatEveryTriangleGives) {
  const model::MeshModel& engine = corpusModel(kEngine);
  ASSERT_GT(engine.triangleCount(), 10000u);
  const glm::dmat4 world = model::worldFromModel(engine, placementOfSize(engine, 0.3, {0.05, -0.02}, 0.4));
  const auto start = std::chrono::steady_clock::now();
  const TriangleScene scene(engine, world);
  const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("2CylinderEngine: %zu triangles (%zu degenerate), %zu nodes, depth %d, built in %.0f ms\n",
              scene.triangleCount(), scene.degenerateCount(), scene.nodeCount(), scene.depth(), build_ms);
  EXPECT_EQ(scene.triangleCount(), engine.triangleCount());
  EXPECT_LT(scene.depth(), 96);
  // Each brute-force ray tests all 121496 triangles (~4 ms a ray): 1000 rays
  // keep this near 4 s while putting hundreds of rays through every part.
  // OccludedAgreesWithIntersect sends 20000 more through the BVH alone.
  expectBvhMatchesEveryTriangle(scene, 1000, 1, 0.4);
}

TEST(TriangleBvh, PlacedBoxClosestHitIsWhatEveryTriangleGives) {
  const model::MeshModel& box = corpusModel(kBox);
  const TriangleScene scene(box, model::worldFromModel(box, placementOfSize(box, 0.2, {0.1, -0.2}, 0.7)));
  EXPECT_EQ(scene.triangleCount(), 12u);
  EXPECT_EQ(scene.degenerateCount(), 0u);
  expectBvhMatchesEveryTriangle(scene, 20000, 2, 0.4);
}

// The placed BoxTextured unturned is the box [x +- 0.1] x [y +- 0.1] x
// [0, 0.2]: the slab test on that box gives the distance to the face and
// its outward normal. Its vertices are +-0.5 in float, scaled by 0.2 and
// moved: the box's faces are where the closed form says to ~1e-17 m, and
// the hit's t, from a few dozen double operations on coordinates ~0.5 m, is
// good to ~1e-15 m; 1e-13 m leaves margin and still tells a wrong face
// (millimetres off) from the right one.
TEST(TriangleBvh, PlacedBoxHitsAtTheAnalyticBoxFace) {
  const model::MeshModel& box = corpusModel(kBox);
  model::ModelPlacement placement;
  placement.position_m = {0.1, -0.2};
  placement.scale = 0.2;
  const TriangleScene scene(box, model::worldFromModel(box, placement));
  const glm::dvec3 low(0.0, -0.3, 0.0), high(0.2, -0.1, 0.2);
  EXPECT_NEAR(glm::length(scene.bounds().min_w - low), 0.0, 1e-15);
  EXPECT_NEAR(glm::length(scene.bounds().max_w - high), 0.0, 1e-15);
  std::mt19937_64 rng(3);
  const glm::dvec3 centre = 0.5 * (low + high);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const glm::dvec3 origin = centre + 0.4 * uniformSphere(rng);
    const glm::dvec3 dir = glm::normalize(pointIn({low - 0.02, high + 0.02}, rng) - origin);
    // The slab test, and the axis whose slab the ray enters last: the face.
    double t_near = -kInf, t_far = kInf;
    glm::dvec3 normal(0.0);
    for (int axis = 0; axis < 3; ++axis) {
      const double t0 = (low[axis] - origin[axis]) / dir[axis], t1 = (high[axis] - origin[axis]) / dir[axis];
      const double enter = std::min(t0, t1);
      if (enter > t_near) {
        t_near = enter;
        normal = glm::dvec3(0.0);
        normal[axis] = dir[axis] > 0.0 ? -1.0 : 1.0;
      }
      t_far = std::min(t_far, std::max(t0, t1));
    }
    const bool analytic_hit = t_near <= t_far && t_near > 0.0;
    const std::optional<TriangleHit> hit = scene.intersect(origin, dir, kInf);
    // A ray within 1e-12 m of an edge may go either way by rounding.
    if (analytic_hit != hit.has_value() && std::abs(t_far - t_near) < 1e-12) continue;
    ASSERT_EQ(analytic_hit, hit.has_value()) << i;
    if (!hit) continue;
    ++hits;
    EXPECT_NEAR(hit->t, t_near, 1e-13) << i;
    EXPECT_NEAR(glm::length(hit->geometric_normal - normal), 0.0, 1e-12) << i;
    // The file's normals are the faces', in float: 1e-6.
    EXPECT_NEAR(glm::length(hit->shading_normal - normal), 0.0, 1e-6) << i;
    EXPECT_FALSE(hit->back_face);
    EXPECT_EQ(hit->material, 0);
  }
  EXPECT_GT(hits, 10000);
}

// A closed mesh with shared vertices: rays from inside must hit. Rays aimed
// exactly at vertices and at points of shared edges are where a test that is
// not watertight lets rays through (each triangle's edge test rounding the
// other way); the watertight test's shared edge functions cannot.
void expectNoRayEscapes(const TriangleScene& scene, const std::vector<glm::dvec3>& targets,
                        const std::vector<glm::dvec3>& insides, bool back_faces_from_inside) {
  int misses = 0, front = 0, rays = 0;
  for (const glm::dvec3& origin : insides)
    for (const glm::dvec3& target : targets) {
      const glm::dvec3 dir = glm::normalize(target - origin);
      const std::optional<TriangleHit> hit = scene.intersect(origin, dir, kInf);
      ++rays;
      if (!hit) {
        ++misses;
        continue;
      }
      if (!hit->back_face) ++front;
      if (!scene.occluded(origin, dir, kInf)) ++misses;
    }
  EXPECT_EQ(misses, 0) << "of " << rays << " rays";
  if (back_faces_from_inside) {
    EXPECT_EQ(front, 0) << "the faces are wound outwards: from inside, all back faces";
  }
}

std::vector<glm::dvec3> edgeAndVertexTargets(const TriangleScene& scene, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> targets;
  for (std::size_t i = 0; i < scene.triangleCount(); ++i) {
    const auto p = scene.vertices(i);
    for (int k = 0; k < 3; ++k) {
      targets.push_back(p[k]);
      targets.push_back(0.5 * (p[k] + p[(k + 1) % 3]));
      const double f = u(rng);
      targets.push_back((1.0 - f) * p[k] + f * p[(k + 1) % 3]);
    }
  }
  return targets;
}

TEST(TriangleBvh, NoRayEscapesTheClosedBox) {
  const model::MeshModel& box = corpusModel(kBox);
  const TriangleScene scene(box, model::worldFromModel(box, placementOfSize(box, 0.2, {0.1, -0.2}, 0.3)));
  std::mt19937_64 rng(4);
  const std::vector<glm::dvec3> targets = edgeAndVertexTargets(scene, rng);
  // The centre (each ray to a corner or edge point runs exactly through it
  // by symmetry, up to rounding) and random points inside.
  const glm::dvec3 centre = 0.5 * (scene.bounds().min_w + scene.bounds().max_w);
  std::vector<glm::dvec3> insides{centre};
  for (int i = 0; i < 300; ++i) insides.push_back(centre + 0.05 * glm::dvec3(uniformSphere(rng)));
  expectNoRayEscapes(scene, targets, insides, true);
}

// An icosahedron subdivided three times onto the unit sphere: 1280
// triangles sharing 642 vertices, wound outwards.
model::MeshModel icosphere() {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> v{{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::uint32_t> f{0, 11, 5, 0, 5,  1,  0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                               6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (glm::dvec3& p : v) p = glm::normalize(p);
  for (int level = 0; level < 3; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      if (auto it = middle.find(key); it != middle.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return middle[key] = static_cast<std::uint32_t>(v.size() - 1);
    };
    std::vector<std::uint32_t> next;
    for (std::size_t i = 0; i < f.size(); i += 3) {
      const std::uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      const std::uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f = std::move(next);
  }
  model::MeshModel m;
  model::Primitive p;
  for (const glm::dvec3& q : v) p.positions_m.push_back(glm::vec3(q));
  p.indices = f;
  m.primitives.push_back(p);
  return m;
}

TEST(TriangleBvh, NoRayEscapesTheClosedSphereMesh) {
  const model::MeshModel sphere = icosphere();
  ASSERT_EQ(sphere.triangleCount(), 1280u);
  glm::dmat4 world(0.05);
  world[3] = glm::dvec4(0.02, -0.03, 0.05, 1.0);
  const TriangleScene scene(sphere, world);
  std::mt19937_64 rng(5);
  const std::vector<glm::dvec3> targets = edgeAndVertexTargets(scene, rng);
  std::vector<glm::dvec3> insides{glm::dvec3(world[3])};
  for (int i = 0; i < 10; ++i) insides.push_back(glm::dvec3(world[3]) + 0.02 * uniformSphere(rng));
  expectNoRayEscapes(scene, targets, insides, true);
  // And 200000 rays in random directions from random points inside.
  int misses = 0;
  for (int i = 0; i < 200000; ++i) {
    const glm::dvec3 origin = glm::dvec3(world[3]) + 0.04 * std::cbrt(std::uniform_real_distribution<double>(0, 1)(rng)) *
                                                         uniformSphere(rng);
    if (!scene.intersect(origin, uniformSphere(rng), kInf)) ++misses;
  }
  EXPECT_EQ(misses, 0);
}

// occluded() is "intersect() finds something closer than t_max", for t_max
// below, around and beyond the closest hit. The two share their triangle
// test, so they agree exactly.
TEST(TriangleBvh, OccludedAgreesWithIntersect) {
  const model::MeshModel& engine = corpusModel(kEngine);
  const TriangleScene scene(engine, model::worldFromModel(engine, placementOfSize(engine, 0.3, {0.0, 0.0}, -1.1)));
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  int occluded_count = 0, rays = 0;
  for (const auto& [origin, dir] : raysAround(scene, 20000, 7)) {
    const std::optional<TriangleHit> hit = scene.intersect(origin, dir, kInf);
    EXPECT_EQ(scene.occluded(origin, dir, kInf), hit.has_value());
    const double t_max = hit ? hit->t * u(rng) : u(rng);
    const bool expected = hit && hit->t < t_max;
    EXPECT_EQ(scene.occluded(origin, dir, t_max), expected);
    // intersect() under the same t_max: nothing, or that same closest hit.
    const std::optional<TriangleHit> limited = scene.intersect(origin, dir, t_max);
    EXPECT_EQ(limited.has_value(), expected);
    if (limited) {
      EXPECT_EQ(limited->t, hit->t);
    }
    occluded_count += expected;
    ++rays;
  }
  EXPECT_GT(occluded_count, rays / 5);
  EXPECT_LT(occluded_count, rays * 4 / 5);
}

// Zero-area triangles (a repeated vertex, three collinear points, one point
// thrice) are kept for their index but never hit, and nothing comes out NaN:
// not rays at them from any side, not rays in their line, not a ray edge-on
// to a good triangle, not a zero or NaN direction.
TEST(TriangleBvh, DegenerateTrianglesNeverHit) {
  model::MeshModel m;
  model::Primitive p;
  p.positions_m = {{0, 0, 0}, {1, 0, 0}, {1, 0, 0},   // a repeated vertex
                   {0, 0, 1}, {1, 0, 1}, {2, 0, 1},   // collinear
                   {0, 0, 2}, {0, 0, 2}, {0, 0, 2},   // a point
                   {0, 0, 3}, {1, 0, 3}, {0, 1, 3}};  // a good one, at z = 3
  for (std::uint32_t i = 0; i < 12; ++i) p.indices.push_back(i);
  m.primitives.push_back(p);
  const TriangleScene scene(m, glm::dmat4(1.0));
  EXPECT_EQ(scene.triangleCount(), 4u);
  EXPECT_EQ(scene.degenerateCount(), 3u);
  EXPECT_TRUE(scene.isDegenerate(0) && scene.isDegenerate(1) && scene.isDegenerate(2) && !scene.isDegenerate(3));
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const int which = i % 3;
    // A point of the degenerate triangle: on its segment (or its point).
    const double f = which == 2 ? 0.0 : u(rng) * (which == 1 ? 2.0 : 1.0);
    const glm::dvec3 target(f, 0.0, which);
    // From anywhere, and every tenth ray along the segment's own line.
    const glm::dvec3 dir = i % 10 == 0 ? glm::dvec3(1.0, 0.0, 0.0) : uniformSphere(rng);
    const glm::dvec3 origin = target - 2.0 * dir;
    for (const auto& hit : {scene.intersect(origin, dir, kInf), scene.intersectEveryTriangle(origin, dir, kInf)}) {
      if (!hit) continue;
      EXPECT_EQ(hit->triangle, 3u) << "only the good triangle can be hit";
      EXPECT_TRUE(finite(*hit));
    }
  }
  // Edge-on to the good triangle, in its plane: no area to cross.
  EXPECT_FALSE(scene.intersect({-1.0, 0.25, 3.0}, {1.0, 0.0, 0.0}, kInf));
  EXPECT_FALSE(scene.intersect({0.2, 0.2, 4.0}, {0.0, 0.0, 0.0}, kInf));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(scene.intersect({0.2, 0.2, 4.0}, {0.0, nan, -1.0}, kInf));
  EXPECT_FALSE(scene.intersect({nan, 0.2, 4.0}, {0.0, 0.0, -1.0}, kInf));
  EXPECT_FALSE(scene.occluded({0.2, 0.2, 4.0}, {0.0, 0.0, 0.0}, kInf));
  // And the good triangle is hit where it is.
  const std::optional<TriangleHit> hit = scene.intersect({0.2, 0.2, 4.0}, {0.0, 0.0, -1.0}, kInf);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->triangle, 3u);
  EXPECT_NEAR(hit->t, 1.0, 1e-15);
}

// A hit mixes the vertex attributes by its barycentrics; normals go through
// the inverse transpose (a stretched model's normals tilt the other way); a
// mirroring transform keeps the geometric normal on glTF's front side; a
// primitive without normals shades flat. Float inputs: 1e-7.
TEST(TriangleBvh, HitCarriesTheVertexAttributes) {
  model::MeshModel m;
  model::Primitive p;
  p.positions_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const glm::vec3 tilted = glm::normalize(glm::vec3(1, 1, 1));
  p.normals = {tilted, tilted, {0, 0, 1}};
  p.uv0 = {{0, 0}, {1, 0}, {0, 1}};
  p.uv1 = {{0.5f, 0.5f}, {0.5f, 0.5f}, {0.5f, 1.5f}};
  p.colors = {{1, 0, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 0.5f}};
  p.indices = {0, 1, 2};
  p.material = 2;
  m.primitives.push_back(p);

  glm::dmat4 stretch(1.0);
  stretch[0][0] = 2.0;  // x twice as long
  const TriangleScene scene(m, stretch);
  // The point with weights (0.25, 0.5, 0.25) is (0.5, 0.25, 0) in the model,
  // (1.0, 0.25, 0) stretched.
  const std::optional<TriangleHit> hit = scene.intersect({1.0, 0.25, 1.0}, {0.0, 0.0, -1.0}, kInf);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(glm::length(hit->barycentric - glm::dvec3(0.25, 0.5, 0.25)), 0.0, 1e-12);
  EXPECT_NEAR(glm::length(hit->uv0 - glm::dvec2(0.5, 0.25)), 0.0, 1e-7);
  EXPECT_NEAR(glm::length(hit->uv1 - glm::dvec2(0.5, 0.75)), 0.0, 1e-7);
  EXPECT_NEAR(glm::length(hit->color - glm::dvec4(0.25, 0.5, 0.25, 0.875)), 0.0, 1e-7);
  EXPECT_EQ(hit->material, 2);
  EXPECT_FALSE(hit->back_face);
  EXPECT_NEAR(glm::length(hit->geometric_normal - glm::dvec3(0, 0, 1)), 0.0, 1e-15);
  // (1, 1, 1) / sqrt 3 through diag(1/2, 1, 1): (0.5, 1, 1) / 1.5; mixed
  // 3:1 (weights 0.25 + 0.5 against 0.25) with (0, 0, 1), renormalised.
  const glm::dvec3 vertex_normal = glm::dvec3(0.5, 1.0, 1.0) / 1.5;
  const glm::dvec3 expected = glm::normalize(0.75 * vertex_normal + 0.25 * glm::dvec3(0, 0, 1));
  EXPECT_NEAR(glm::length(hit->shading_normal - expected), 0.0, 1e-7);

  // Mirrored in x: the triangle winds clockwise seen from +z now, but glTF's
  // front side is still +z.
  glm::dmat4 mirror(1.0);
  mirror[0][0] = -1.0;
  const TriangleScene mirrored(m, mirror);
  const std::optional<TriangleHit> from_above = mirrored.intersect({-0.2, 0.2, 1.0}, {0.0, 0.0, -1.0}, kInf);
  ASSERT_TRUE(from_above);
  EXPECT_NEAR(glm::length(from_above->geometric_normal - glm::dvec3(0, 0, 1)), 0.0, 1e-15);
  EXPECT_FALSE(from_above->back_face);

  // No normals: flat. No UVs or colours: zero and white. From below: back face.
  m.primitives[0].normals.clear();
  m.primitives[0].uv0.clear();
  m.primitives[0].uv1.clear();
  m.primitives[0].colors.clear();
  const TriangleScene flat(m, glm::dmat4(1.0));
  const std::optional<TriangleHit> from_below = flat.intersect({0.2, 0.2, -1.0}, {0.0, 0.0, 1.0}, kInf);
  ASSERT_TRUE(from_below);
  EXPECT_TRUE(from_below->back_face);
  EXPECT_EQ(from_below->shading_normal, glm::dvec3(0, 0, 1));
  EXPECT_EQ(from_below->uv0, glm::dvec2(0.0));
  EXPECT_NEAR(glm::length(from_below->color - glm::dvec4(1.0)), 0.0, 1e-15);  // weights sum to 1 to rounding
}

// The self-hit guard: a ray leaving a hit point does not find the surface it
// left, while a surface 1e-6 of the scene's size away is still found.
TEST(TriangleBvh, RayLeavingASurfaceDoesNotHitItAgain) {
  const model::MeshModel& box = corpusModel(kBox);
  model::ModelPlacement placement;
  placement.scale = 0.2;
  const TriangleScene scene(box, model::worldFromModel(box, placement));
  EXPECT_GT(scene.t_min(), 0.0);
  EXPECT_LT(scene.t_min(), 1e-9);  // 1e-9 of a 0.35 m diagonal
  std::mt19937_64 rng(9);
  int again = 0;
  for (int i = 0; i < 10000; ++i) {
    const glm::dvec3 origin = glm::dvec3(0.0, 0.0, 0.1) + 0.5 * uniformSphere(rng);
    const glm::dvec3 dir = glm::normalize(glm::dvec3(0.0, 0.0, 0.1) + 0.05 * uniformSphere(rng) - origin);
    const std::optional<TriangleHit> hit = scene.intersect(origin, dir, kInf);
    if (!hit) continue;
    glm::dvec3 out = uniformSphere(rng);
    if (glm::dot(out, hit->geometric_normal) < 0.0) out = -out;
    if (glm::dot(out, hit->geometric_normal) < 1e-3) continue;  // grazing: the guard's stated limit
    if (scene.occluded(origin + hit->t * dir, out, kInf)) ++again;
  }
  EXPECT_EQ(again, 0) << "a convex box: nothing to hit from outside it";
}

}  // namespace
}  // namespace probelight::sim
