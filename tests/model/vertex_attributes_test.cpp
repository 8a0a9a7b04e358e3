#include "model/vertex_attributes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace probelight::model {
namespace {

// A unit quad in the z = 0 plane as two triangles, UVs along x and y.
Primitive quad(bool mirrored_u = false) {
  Primitive p;
  p.positions_m = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  p.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  const float u1 = mirrored_u ? 0.0f : 1.0f, u0 = mirrored_u ? 1.0f : 0.0f;
  p.uv0 = {{u0, 0}, {u1, 0}, {u1, 1}, {u0, 1}};
  p.indices = {0, 1, 2, 0, 2, 3};
  return p;
}

TEST(VertexAttributes, FlatNormalsAreTheFaceNormalsAsWoundAndDegenerateOnesAreFinite) {
  Primitive p;
  p.positions_m = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 2, 2}};
  p.uv0 = {{0, 0}, {1, 0}, {0, 1}, {0.5f, 0.5f}, {1, 1}};
  // Counter-clockwise seen from +z; then from -y... and one with all corners equal.
  p.indices = {0, 1, 2, 0, 3, 1, 4, 4, 4};
  const Primitive flat = withFlatNormals(p);
  ASSERT_EQ(flat.positions_m.size(), 9u);
  ASSERT_EQ(flat.indices.size(), 9u);
  ASSERT_EQ(flat.uv0.size(), 9u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(flat.normals[k], glm::vec3(0, 0, 1));
    // (0,0,1) x (1,0,0) = (0,1,0)... the face (0, 3, 1): e1 = (0,0,1), e2 = (1,0,0).
    EXPECT_EQ(flat.normals[3 + k], glm::vec3(0, 1, 0));
    EXPECT_TRUE(std::isfinite(flat.normals[6 + k].x) && glm::length(flat.normals[6 + k]) == 1.0f);
    EXPECT_EQ(flat.indices[k], static_cast<std::uint32_t>(k));
  }
  EXPECT_EQ(flat.uv0[4], glm::vec2(0.5f, 0.5f));
}

TEST(VertexAttributes, TangentsFollowTheUAxisWithTheHandednessOfTheUvs) {
  for (const bool mirrored : {false, true}) {
    const Primitive p = quad(mirrored);
    const std::vector<glm::vec4> t = tangentsFromUvs(p.positions_m, p.normals, p.uv0, p.indices);
    ASSERT_EQ(t.size(), 4u);
    for (const glm::vec4& tangent : t) {
      // u grows along +x (or -x when mirrored); v along +y: B = +y either way,
      // so (T, B, N) is right-handed unmirrored, left-handed mirrored.
      EXPECT_NEAR(tangent.x, mirrored ? -1.0f : 1.0f, 1e-6f);
      EXPECT_NEAR(tangent.y, 0.0f, 1e-6f);
      EXPECT_NEAR(tangent.z, 0.0f, 1e-6f);
      EXPECT_EQ(tangent.w, mirrored ? -1.0f : 1.0f);
      // glTF's bitangent = cross(N, T) * w must be +y, the direction v grows.
      const glm::vec3 bitangent = glm::cross(glm::vec3(0, 0, 1), glm::vec3(tangent)) * tangent.w;
      EXPECT_NEAR(bitangent.y, 1.0f, 1e-6f);
    }
  }
}

TEST(VertexAttributes, TangentsAreOrthogonalUnitVectorsEvenWithoutUsableUvs) {
  Primitive p = quad();
  p.normals = {glm::normalize(glm::vec3(0.3f, 0, 1)), {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  p.uv0 = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};  // no UV area: no direction
  for (const auto& uv : {p.uv0, std::vector<glm::vec2>{}}) {
    const std::vector<glm::vec4> t = tangentsFromUvs(p.positions_m, p.normals, uv, p.indices);
    for (std::size_t i = 0; i < t.size(); ++i) {
      EXPECT_NEAR(glm::length(glm::vec3(t[i])), 1.0f, 1e-6f);
      EXPECT_NEAR(glm::dot(glm::vec3(t[i]), p.normals[i]), 0.0f, 1e-6f);
      EXPECT_EQ(t[i].w, 1.0f);
    }
  }
  // With UVs, a tilted normal still gets an orthogonal tangent (Gram-Schmidt).
  const std::vector<glm::vec4> t = tangentsFromUvs(p.positions_m, p.normals, quad().uv0, p.indices);
  EXPECT_NEAR(glm::dot(glm::vec3(t[0]), p.normals[0]), 0.0f, 1e-6f);
  EXPECT_GT(t[0].x, 0.9f);
}

TEST(VertexAttributes, ShortIndexPiecesAddressAtMostTheirLimitAndKeepEveryTriangle) {
  // 200,000 triangles over 150,000 vertices in random order: more than
  // 16-bit indices can address at once.
  std::mt19937 random(7);
  std::uniform_int_distribution<std::uint32_t> vertex(0, 149'999);
  std::vector<std::uint32_t> indices(600'000);
  for (auto& index : indices) index = vertex(random);
  for (const std::size_t limit : {std::size_t{65536}, std::size_t{1000}}) {
    const std::vector<ShortIndexPiece> pieces = splitForShortIndices(indices, limit);
    ASSERT_GT(pieces.size(), 1u);
    std::vector<std::uint32_t> rebuilt;
    for (const ShortIndexPiece& piece : pieces) {
      EXPECT_LE(piece.vertices.size(), limit);
      EXPECT_EQ(std::set<std::uint32_t>(piece.vertices.begin(), piece.vertices.end()).size(), piece.vertices.size());
      EXPECT_EQ(piece.indices.size() % 3, 0u);
      for (std::uint16_t local : piece.indices) {
        ASSERT_LT(local, piece.vertices.size());
        rebuilt.push_back(piece.vertices[local]);
      }
    }
    EXPECT_EQ(rebuilt, indices) << limit;
  }
  // A small primitive stays one piece with its own numbering.
  const std::vector<ShortIndexPiece> one = splitForShortIndices({5, 9, 7, 7, 9, 100});
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].vertices, (std::vector<std::uint32_t>{5, 9, 7, 100}));
  EXPECT_EQ(one[0].indices, (std::vector<std::uint16_t>{0, 1, 2, 2, 1, 3}));
  EXPECT_TRUE(splitForShortIndices({}).empty());
}

}  // namespace
}  // namespace probelight::model
