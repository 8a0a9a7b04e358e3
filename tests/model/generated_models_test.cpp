// The generated shapes: where their vertices lie, which way their triangles
// face, how many there are, and the volume they close (the divergence
// theorem: a consistently outward-wound closed surface encloses
// sum p0 . (p1 x p2) / 6 > 0; one triangle wound the wrong way changes it).
#include <gtest/gtest.h>

#include <cmath>

#include "core/math_constants.hpp"
#include "model/generated_models.hpp"

namespace probelight::model {
namespace {

double enclosedVolume(const MeshModel& model) {
  double volume = 0.0;
  for (const Primitive& p : model.primitives)
    for (std::size_t t = 0; t + 2 < p.indices.size(); t += 3) {
      const glm::dvec3 a = p.positions_m[p.indices[t]], b = p.positions_m[p.indices[t + 1]],
                       c = p.positions_m[p.indices[t + 2]];
      volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
  return volume;
}

// Every triangle's winding agrees with its vertex normals: (p1 - p0) x
// (p2 - p0) points to the side the normals do.
void expectWindingMatchesNormals(const MeshModel& model) {
  for (const Primitive& p : model.primitives)
    for (std::size_t t = 0; t + 2 < p.indices.size(); t += 3) {
      const std::uint32_t i0 = p.indices[t], i1 = p.indices[t + 1], i2 = p.indices[t + 2];
      const glm::dvec3 g = glm::cross(glm::dvec3(p.positions_m[i1] - p.positions_m[i0]),
                                      glm::dvec3(p.positions_m[i2] - p.positions_m[i0]));
      ASSERT_GT(glm::length(g), 0.0) << "triangle " << t / 3 << " has no area";
      const glm::dvec3 n = glm::dvec3(p.normals[i0] + p.normals[i1] + p.normals[i2]);
      EXPECT_GT(glm::dot(g, n), 0.0) << "triangle " << t / 3;
    }
}

TEST(GeneratedModels, SphereVerticesLieOnItWithRadialNormalsAndItsVolumeIsInscribed) {
  const double radius_m = 0.05;
  const int rings = 24;
  const MeshModel sphere = sphereModel(radius_m, rings, Material{});
  ASSERT_EQ(sphere.primitives.size(), 1u);
  EXPECT_EQ(sphere.triangleCount(), static_cast<std::size_t>(4 * rings * rings - 4 * rings));
  const Primitive& p = sphere.primitives[0];
  for (std::size_t i = 0; i < p.positions_m.size(); ++i) {
    const glm::dvec3 v(p.positions_m[i]);
    // float storage: 1e-7 of the radius
    EXPECT_NEAR(glm::length(v), radius_m, 1e-7) << i;
    EXPECT_NEAR(glm::dot(glm::dvec3(p.normals[i]), v / radius_m), 1.0, 1e-6) << i;
  }
  expectWindingMatchesNormals(sphere);
  // The polyhedron is inscribed: inside the sphere, and outside the sphere
  // of radius R cos(pi / rings) (every facet's plane is at least that far
  // from the centre: a facet spans at most pi / rings of arc each way).
  const double volume = enclosedVolume(sphere);
  EXPECT_LT(volume, 4.0 / 3.0 * kPi * std::pow(radius_m, 3));
  EXPECT_GT(volume, 4.0 / 3.0 * kPi * std::pow(radius_m * std::cos(kPi / rings), 3));
  EXPECT_NEAR(sphere.min_m.z, -radius_m, 1e-7);
  EXPECT_NEAR(sphere.max_m.z, radius_m, 1e-7);
}

TEST(GeneratedModels, BowlIsClosedOutwardAndHollow) {
  const double outer_m = 0.05, wall_m = 0.005;
  const int rings = 16;
  const MeshModel bowl = bowlModel(outer_m, wall_m, rings, Material{});
  expectWindingMatchesNormals(bowl);
  // The wall's volume: between two hemispheres. Inscribed, as the sphere.
  const double r = outer_m - wall_m;
  const double exact = 2.0 / 3.0 * kPi * (std::pow(outer_m, 3) - std::pow(r, 3));
  const double volume = enclosedVolume(bowl);
  const double c3 = std::pow(std::cos(kPi / (2 * rings)), 3);
  EXPECT_GT(volume, 2.0 / 3.0 * kPi * (c3 * std::pow(outer_m, 3) - std::pow(r, 3)));
  EXPECT_LT(volume, 2.0 / 3.0 * kPi * (std::pow(outer_m, 3) - c3 * std::pow(r, 3)));
  EXPECT_GT(volume, 0.0) << exact;
  // The inside faces up and in: its lowest vertex's normal points up.
  EXPECT_NEAR(bowl.min_m.z, -outer_m, 1e-7);
  EXPECT_NEAR(bowl.max_m.z, 0.0, 1e-7);
}

TEST(GeneratedModels, BoxEnclosesItsVolumeWithFlatOutwardFaces) {
  const glm::dvec3 size(0.04, 0.06, 0.08);
  const MeshModel box = boxModel(size, Material{});
  EXPECT_EQ(box.triangleCount(), 12u);
  expectWindingMatchesNormals(box);
  // Exact up to float storage of the corners.
  EXPECT_NEAR(enclosedVolume(box), size.x * size.y * size.z, 1e-9);
  for (const glm::vec2& uv : box.primitives[0].uv0) {
    EXPECT_TRUE(uv.x == 0.0f || uv.x == 1.0f);
    EXPECT_TRUE(uv.y == 0.0f || uv.y == 1.0f);
  }
  EXPECT_FLOAT_EQ(box.min_m.x, -0.02f);
  EXPECT_FLOAT_EQ(box.max_m.z, 0.04f);
}

TEST(GeneratedModels, AProfileTooShortGivesNoModel) {
  EXPECT_EQ(surfaceOfRevolution({ProfileRun{{{0.01, 0.0}}}}, 8, Material{}).triangleCount(), 0u);
}

}  // namespace
}  // namespace probelight::model
