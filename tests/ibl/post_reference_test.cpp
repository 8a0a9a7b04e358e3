// Dividing the light an 8-bit map clips between its clipped regions by
// diffuse readings at several normals (ibl/post_reference.hpp), on maps whose
// truth is known exactly: a dim sky with a small, very bright lamp and a
// large region just past the clip, the case where the border's one number
// (in proportion to solid angle) over-lights the large region.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/math_constants.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/irradiance.hpp"
#include "ibl/post_reference.hpp"
#include "ibl/white_reference.hpp"

namespace probelight::ibl {
namespace {

constexpr int kFace = 24;

const glm::dvec3 kLamp = glm::normalize(glm::dvec3(0.6, -0.2, 0.75));
const glm::dvec3 kBoard = glm::normalize(glm::dvec3(-0.3, -0.9, 0.3));

glm::dvec3 trueRadiance(const glm::dvec3& d) {
  if (glm::dot(d, kLamp) > std::cos(glm::radians(5.0))) return glm::dvec3(60.0, 55.0, 50.0);
  if (glm::dot(d, kBoard) > std::cos(glm::radians(22.0))) return glm::dvec3(1.8, 1.7, 1.6);
  return d.z > 0.0 ? glm::dvec3(0.15, 0.18, 0.25) : glm::dvec3(0.06);
}

CubeMapRGB mapOf(bool clip) {
  CubeMapRGB map(kFace);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < kFace; ++y)
      for (int x = 0; x < kFace; ++x) {
        const glm::dvec3 radiance = trueRadiance(cubeTexelCenterDirection(face, x, y, kFace));
        map.texel(face, x, y) = glm::vec3(clip ? glm::min(radiance, glm::dvec3(1.0)) : radiance);
      }
  return map;
}

glm::dvec3 irradianceAt(const CubeMapRGB& map, const glm::dvec3& normal) { return irradianceFromCubeMap(map, normal); }

// Horizontal normals toward a camera at azimuth -80 deg (the side of the
// post it sees), +-45 deg.
std::vector<glm::dvec3> postNormals() {
  std::vector<glm::dvec3> normals;
  for (double offset = -45.0; offset <= 45.0; offset += 15.0) {
    const double a = glm::radians(-80.0 + offset);
    normals.push_back({std::cos(a), std::sin(a), 0.0});
  }
  return normals;
}

struct ClippedWorld {
  CubeMapRGB truth = mapOf(false), original = mapOf(true), corrected = mapOf(true);
  WhiteBorderReading border;
  std::vector<DiffuseReference> references;
};

ClippedWorld borderCorrected() {
  ClippedWorld setup;
  const double albedo = 0.85;
  glm::dvec3 e_up(0.0);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < kFace; ++y)
      for (int x = 0; x < kFace; ++x) {
        const glm::dvec3 omega = cubeTexelCenterDirection(face, x, y, kFace);
        if (omega.z > 0.0) e_up += glm::dvec3(setup.truth.texel(face, x, y)) * omega.z * cubeTexelSolidAngle(x, y, kFace);
      }
  setup.border.status = WhiteBorderStatus::kMeasured;
  setup.border.linear_rgb = e_up * albedo / kPi;
  setup.border.patches_lit = 16;
  const WhiteReferenceResult result =
      correctClippedWithWhiteBorder(setup.corrected, nullptr, setup.border, albedo, 1.0);
  EXPECT_EQ(result.status, WhiteReferenceStatus::kCorrected) << result.message;
  setup.references.push_back(borderReference(setup.border, albedo));
  EXPECT_NEAR(luminance(setup.references[0].irradiance_rgb), luminance(e_up), 1e-9 * luminance(e_up));
  for (const glm::dvec3& normal : postNormals()) setup.references.push_back({normal, irradianceAt(setup.truth, normal), 20});
  return setup;
}

// Mean relative error of the map's irradiance against the truth over
// normals facing the camera's side (a sphere's visible half).
double meanErrorFacingTheCamera(const CubeMapRGB& map, const CubeMapRGB& truth) {
  const glm::dvec3 toward(std::cos(glm::radians(-80.0)), std::sin(glm::radians(-80.0)), 0.0);
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < 400; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / 400.0, r = std::sqrt(1.0 - z * z), a = i * kPi * (3.0 - std::sqrt(5.0));
    const glm::dvec3 normal(r * std::cos(a), r * std::sin(a), z);
    if (glm::dot(normal, toward) < 0.2) continue;
    const double expected = luminance(irradianceAt(truth, normal));
    sum += std::abs(luminance(irradianceAt(map, normal)) - expected) / expected;
    ++count;
  }
  return sum / count;
}

TEST(DiffuseReferences, DivideTheClippedLightBetweenALampAndABrightBoard) {
  ClippedWorld setup = borderCorrected();
  const double border_only = meanErrorFacingTheCamera(setup.corrected, setup.truth);
  const DiffuseFit fit = fitClippedRegionsToReferences(setup.corrected, setup.original, nullptr, 1.0, nullptr,
                                                       setup.references);
  ASSERT_EQ(fit.status, DiffuseFitStatus::kRefined) << fit.message;
  const double refined = meanErrorFacingTheCamera(setup.corrected, setup.truth);
  std::printf("[ post     ] mean irradiance error facing the camera: border alone %.1f%%, with the post %.1f%%; "
              "readings off by %.1f%% rms before, %.1f%% after (%zu regions)\n",
              100.0 * border_only, 100.0 * refined, 100.0 * fit.rms_relative_before, 100.0 * fit.rms_relative_after,
              fit.region_scale_rgb.size());
  // The border alone gives the board the lamp's light: far off.
  EXPECT_GT(border_only, 0.15);
  // The readings are exact and the model holds them exactly (each region's
  // shape is the truth's, only its level is unknown) but for texels the
  // lamp's and the board's edges cut (their clipped value is not a step):
  // a few percent.
  EXPECT_LT(refined, 0.03);
  EXPECT_LT(fit.rms_relative_after, 0.01);
  EXPECT_GT(fit.rms_relative_before, 0.15);
  // The board gets less than the border's share, the lamp more.
  for (std::size_t k = 0; k < fit.region_scale_rgb.size(); ++k) {
    if (glm::dot(fit.region_direction_w[k], kLamp) > 0.99) {
      EXPECT_GT(fit.region_scale_rgb[k].g, 1.5);
    }
    if (glm::dot(fit.region_direction_w[k], kBoard) > 0.95) {
      EXPECT_LT(fit.region_scale_rgb[k].g, 0.5);
    }
  }
  // The ground's irradiance stays the border's.
  EXPECT_NEAR(luminance(irradianceAt(setup.corrected, {0.0, 0.0, 1.0})) / luminance(setup.references[0].irradiance_rgb),
              1.0, 0.01);
}

// A reading darker than what the ball's unclipped light alone gives there
// (a post in shade, an albedo set too high) changes nothing and says so;
// nothing clipped, or no reading, is nothing to fit.
TEST(DiffuseReferences, AReadingDarkerThanTheUnclippedLightIsRefused) {
  ClippedWorld setup = borderCorrected();
  const CubeMapRGB before = setup.corrected;
  setup.references.back().irradiance_rgb *= 0.2;
  const DiffuseFit fit = fitClippedRegionsToReferences(setup.corrected, setup.original, nullptr, 1.0, nullptr,
                                                       setup.references);
  EXPECT_EQ(fit.status, DiffuseFitStatus::kInconsistent);
  EXPECT_NE(fit.message.find("albedo"), std::string::npos) << fit.message;
  for (int face = 0; face < kCubeFaceCount; ++face) EXPECT_EQ(setup.corrected.faces[face], before.faces[face]);

  CubeMapRGB unclipped = setup.original;
  EXPECT_EQ(fitClippedRegionsToReferences(unclipped, setup.original, nullptr, 1.0, nullptr, setup.references).status,
            DiffuseFitStatus::kNothingToFit);
  EXPECT_EQ(fitClippedRegionsToReferences(setup.corrected, setup.original, nullptr, 1.0, nullptr, {}).status,
            DiffuseFitStatus::kNothingToFit);
}

}  // namespace
}  // namespace probelight::ibl
