#include "model/generated_models.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace probelight::model {
namespace {

// The bounds every caller of a MeshModel relies on (placement rests the
// lowest vertex on the ground).
void updateBounds(MeshModel& model) {
  bool any = false;
  for (const Primitive& p : model.primitives)
    for (const glm::vec3& v : p.positions_m) {
      model.min_m = any ? glm::min(model.min_m, v) : v;
      model.max_m = any ? glm::max(model.max_m, v) : v;
      any = true;
    }
}

MeshModel withOneMaterial(Primitive primitive, const Material& material, const char* source) {
  MeshModel model;
  model.source = source;
  primitive.material = 0;
  model.primitives.push_back(std::move(primitive));
  model.materials.push_back(material);
  updateBounds(model);
  return model;
}

}  // namespace

MeshModel surfaceOfRevolution(const std::vector<ProfileRun>& runs, int segments, const Material& material) {
  Primitive primitive;
  segments = std::max(3, segments);
  double profile_length = 0.0;
  for (const ProfileRun& run : runs)
    for (std::size_t i = 1; i < run.points_rz.size(); ++i)
      profile_length += glm::length(run.points_rz[i] - run.points_rz[i - 1]);
  double along = 0.0;
  for (const ProfileRun& run : runs) {
    const std::vector<glm::dvec2>& p = run.points_rz;
    if (p.size() < 2) continue;
    // The normal in the (r, z) plane: the tangent turned clockwise, averaged
    // over the two segments at an inner point.
    std::vector<glm::dvec2> normals(p.size());
    const bool given = run.normals_rz.size() == p.size();
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (given) {
        normals[i] = glm::normalize(run.normals_rz[i]);
        continue;
      }
      glm::dvec2 tangent(0.0);
      if (i > 0) tangent += glm::normalize(p[i] - p[i - 1]);
      if (i + 1 < p.size()) tangent += glm::normalize(p[i + 1] - p[i]);
      const glm::dvec2 n(tangent.y, -tangent.x);
      normals[i] = glm::length(n) > 0.0 ? glm::normalize(n) : glm::dvec2(0.0, 1.0);
    }
    const auto first = static_cast<std::uint32_t>(primitive.positions_m.size());
    const int columns = segments + 1;  // the seam's vertices twice, for the UVs
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (i > 0) along += glm::length(p[i] - p[i - 1]);
      for (int j = 0; j < columns; ++j) {
        const double phi = 2.0 * std::numbers::pi * j / segments;
        const double c = std::cos(phi), s = std::sin(phi);
        primitive.positions_m.emplace_back(p[i].x * c, p[i].x * s, p[i].y);
        primitive.normals.emplace_back(normals[i].x * c, normals[i].x * s, normals[i].y);
        primitive.uv0.emplace_back(static_cast<double>(j) / segments,
                                   profile_length > 0.0 ? along / profile_length : 0.0);
      }
    }
    auto at = [&](std::size_t i, int j) { return first + static_cast<std::uint32_t>(i * columns + j); };
    for (std::size_t i = 0; i + 1 < p.size(); ++i)
      for (int j = 0; j < segments; ++j) {
        // (i, j) -> (i, j + 1) runs around, (i, j) -> (i + 1, j) along the
        // profile: around x along points out on the right of the profile.
        if (p[i].x > 0.0) primitive.indices.insert(primitive.indices.end(), {at(i, j), at(i, j + 1), at(i + 1, j)});
        if (p[i + 1].x > 0.0)
          primitive.indices.insert(primitive.indices.end(), {at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
      }
  }
  if (primitive.indices.empty()) return MeshModel{};
  return withOneMaterial(std::move(primitive), material, "generated surface of revolution");
}

MeshModel sphereModel(double radius_m, int rings, const Material& material) {
  rings = std::max(2, rings);
  ProfileRun run;
  for (int k = 0; k <= rings; ++k) {
    const double theta = std::numbers::pi * k / rings;  // from the bottom pole
    const glm::dvec2 radial(k == 0 || k == rings ? 0.0 : std::sin(theta), -std::cos(theta));
    run.points_rz.push_back(radius_m * radial);
    run.normals_rz.push_back(radial);
  }
  MeshModel model = surfaceOfRevolution({run}, 2 * rings, material);
  model.source = "generated sphere";
  return model;
}

MeshModel bowlModel(double outer_radius_m, double wall_m, int rings, const Material& material) {
  rings = std::max(2, rings);
  const double inner_radius_m = std::max(0.0, outer_radius_m - wall_m);
  ProfileRun outside, rim, inside;
  for (int k = 0; k <= rings; ++k) {
    const double theta = 0.5 * std::numbers::pi * k / rings;
    const glm::dvec2 radial(k == 0 ? 0.0 : std::sin(theta), -std::cos(theta));
    outside.points_rz.push_back(outer_radius_m * radial);
    outside.normals_rz.push_back(radial);
  }
  rim.points_rz = {{outer_radius_m, 0.0}, {inner_radius_m, 0.0}};
  for (int k = rings; k >= 0; --k) {
    const double theta = 0.5 * std::numbers::pi * k / rings;
    const glm::dvec2 radial(k == 0 ? 0.0 : std::sin(theta), -std::cos(theta));
    inside.points_rz.push_back(inner_radius_m * radial);
    inside.normals_rz.push_back(-radial);  // the inside faces the centre
  }
  MeshModel model = surfaceOfRevolution({outside, rim, inside}, 4 * rings, material);
  model.source = "generated bowl";
  return model;
}

MeshModel boxModel(const glm::dvec3& size_m, const Material& material) {
  Primitive primitive;
  const glm::dvec3 h = 0.5 * size_m;
  // Each face: its outward normal and two edge directions whose cross
  // product is that normal (so the winding is counter-clockwise outside).
  const glm::dvec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {1.0, -1.0}) {
      const glm::dvec3 n = sign * axes[axis];
      const glm::dvec3 u = axes[(axis + 1) % 3], v = sign * axes[(axis + 2) % 3];
      const auto first = static_cast<std::uint32_t>(primitive.positions_m.size());
      for (int corner = 0; corner < 4; ++corner) {
        const double a = (corner == 1 || corner == 2) ? 1.0 : -1.0, b = corner >= 2 ? 1.0 : -1.0;
        primitive.positions_m.emplace_back(h * (n + a * u + b * v));
        primitive.normals.emplace_back(n);
        primitive.uv0.emplace_back(0.5 * (a + 1.0), 0.5 * (1.0 - b));
      }
      primitive.indices.insert(primitive.indices.end(), {first, first + 1, first + 2, first, first + 2, first + 3});
    }
  MeshModel model = withOneMaterial(std::move(primitive), material, "generated box");
  return model;
}

}  // namespace probelight::model
