#include "model/vertex_attributes.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace probelight::model {

namespace {

template <typename T>
void appendCorner(std::vector<T>& out, const std::vector<T>& in, std::uint32_t index) {
  if (!in.empty()) out.push_back(in[index]);
}

// Any unit vector orthogonal to unit n.
glm::vec3 orthogonalTo(const glm::vec3& n) {
  const glm::vec3 axis = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(axis, n));
}

}  // namespace

Primitive withFlatNormals(const Primitive& primitive) {
  Primitive flat;
  flat.material = primitive.material;
  const std::size_t corners = primitive.indices.size() / 3 * 3;
  for (std::size_t i = 0; i < corners; i += 3) {
    const std::uint32_t a = primitive.indices[i], b = primitive.indices[i + 1], c = primitive.indices[i + 2];
    const glm::vec3 face = glm::cross(primitive.positions_m[b] - primitive.positions_m[a],
                                      primitive.positions_m[c] - primitive.positions_m[a]);
    const float length = glm::length(face);
    const glm::vec3 normal = length > 0.0f && std::isfinite(length) ? face / length : glm::vec3(0, 0, 1);
    for (std::uint32_t index : {a, b, c}) {
      flat.positions_m.push_back(primitive.positions_m[index]);
      flat.normals.push_back(normal);
      appendCorner(flat.tangents, primitive.tangents, index);
      appendCorner(flat.uv0, primitive.uv0, index);
      appendCorner(flat.uv1, primitive.uv1, index);
      appendCorner(flat.colors, primitive.colors, index);
      flat.indices.push_back(static_cast<std::uint32_t>(flat.indices.size()));
    }
  }
  return flat;
}

std::vector<glm::vec4> tangentsFromUvs(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                       const std::vector<glm::vec2>& uv, const std::vector<std::uint32_t>& indices) {
  std::vector<glm::dvec3> du(positions.size(), glm::dvec3(0.0)), dv(positions.size(), glm::dvec3(0.0));
  if (uv.size() == positions.size()) {
    for (std::size_t i = 0; i + 2 < indices.size(); i += 3) {
      const std::uint32_t a = indices[i], b = indices[i + 1], c = indices[i + 2];
      const glm::dvec3 e1 = glm::dvec3(positions[b] - positions[a]), e2 = glm::dvec3(positions[c] - positions[a]);
      const glm::dvec2 t1 = glm::dvec2(uv[b] - uv[a]), t2 = glm::dvec2(uv[c] - uv[a]);
      // [e1 e2] = [dP/du dP/dv] [t1 t2]: dP/du = (e1 t2.y - e2 t1.y) / det, weighted
      // by det (the triangle's UV area, signed) so each triangle counts by its
      // size and a mirrored one keeps its sign.
      const double det = t1.x * t2.y - t2.x * t1.y;
      if (!(std::abs(det) > 0.0) || !std::isfinite(det)) continue;
      const double sign = det > 0.0 ? 1.0 : -1.0;
      const glm::dvec3 along_u = sign * (e1 * t2.y - e2 * t1.y), along_v = sign * (e2 * t1.x - e1 * t2.x);
      for (std::uint32_t index : {a, b, c}) {
        du[index] += along_u;
        dv[index] += along_v;
      }
    }
  }
  std::vector<glm::vec4> tangents(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const glm::dvec3 n = glm::dvec3(i < normals.size() ? normals[i] : glm::vec3(0, 0, 1));
    const glm::dvec3 t = du[i] - n * glm::dot(n, du[i]);
    const double length = glm::length(t);
    if (!(length > 1e-12) || !std::isfinite(length)) {
      tangents[i] = glm::vec4(orthogonalTo(glm::vec3(n)), 1.0f);
      continue;
    }
    const glm::dvec3 unit = t / length;
    const double handedness = glm::dot(glm::cross(n, unit), dv[i]) < 0.0 ? -1.0 : 1.0;
    tangents[i] = glm::vec4(glm::vec3(unit), static_cast<float>(handedness));
  }
  return tangents;
}

std::vector<ShortIndexPiece> splitForShortIndices(const std::vector<std::uint32_t>& indices, std::size_t max_vertices) {
  max_vertices = std::clamp<std::size_t>(max_vertices, 3, 65536);
  std::vector<ShortIndexPiece> pieces;
  std::unordered_map<std::uint32_t, std::uint16_t> local;
  for (std::size_t i = 0; i + 2 < indices.size(); i += 3) {
    std::size_t fresh = 0;
    for (std::size_t k = 0; k < 3; ++k)
      if (!local.count(indices[i + k])) ++fresh;
    if (pieces.empty() || pieces.back().vertices.size() + fresh > max_vertices) {
      pieces.emplace_back();
      local.clear();
    }
    ShortIndexPiece& piece = pieces.back();
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t original = indices[i + k];
      auto [it, inserted] = local.emplace(original, static_cast<std::uint16_t>(piece.vertices.size()));
      if (inserted) piece.vertices.push_back(original);
      piece.indices.push_back(it->second);
    }
  }
  return pieces;
}

}  // namespace probelight::model
