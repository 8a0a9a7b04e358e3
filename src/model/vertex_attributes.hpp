// What a renderer derives from a primitive the file left incomplete, and how
// it fits a GLES2 board's index limits. Pure functions of the arrays.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "model/mesh_model.hpp"

namespace probelight::model {

// glTF 2.0 (3.7.2.1): "When normals are not specified, client
// implementations MUST calculate flat normals". Each triangle gets its own
// three vertices (the index list becomes 0, 1, 2, ...) with its face
// normal, as wound (counter-clockwise front). A degenerate triangle gets
// +Z, so no normal is ever NaN. Every other attribute is carried along.
Primitive withFlatNormals(const Primitive& primitive);

// Per-vertex tangents from the UVs of `uv` (glTF's normal map needs them
// where the file gives none): each triangle's dP/du, accumulated weighted by
// its area in UV, then made orthogonal to the vertex normal
// (Gram-Schmidt), with w = +1 or -1 the handedness of (T, B, N), B the
// accumulated dP/dv. Where the UVs give no direction (degenerate, or no
// UVs at all) the tangent is any unit vector orthogonal to the normal, w = +1.
// Needs normals (one per position); returns one tangent per position.
std::vector<glm::vec4> tangentsFromUvs(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                       const std::vector<glm::vec2>& uv, const std::vector<std::uint32_t>& indices);

// A primitive cut into pieces whose vertices 16-bit indices can address
// (GLES2 without OES_element_index_uint): each piece lists the original
// vertices it uses (`vertices`) and its triangles as indices into that
// list. Triangles keep their order; a piece holds at most max_vertices
// (at most 65536) vertices.
struct ShortIndexPiece {
  std::vector<std::uint32_t> vertices;
  std::vector<std::uint16_t> indices;
};
std::vector<ShortIndexPiece> splitForShortIndices(const std::vector<std::uint32_t>& indices,
                                                  std::size_t max_vertices = 65536);

}  // namespace probelight::model
