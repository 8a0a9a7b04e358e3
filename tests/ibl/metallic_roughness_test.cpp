#include "ibl/metallic_roughness.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace probelight::ibl {
namespace {

const std::vector<double> kDefaultExponents{128.0, 16.0};

double lobeFitError(double alpha, double exponent) {
  double error = 0.0;
  for (int degrees = 1; degrees < 90; ++degrees) {
    const double theta = degrees * M_PI / 180.0;
    const double d = ggxLobeEnergyWithin(alpha, theta) - phongLobeEnergyWithin(exponent, theta);
    error += d * d;
  }
  return error;
}

// The lobes' cumulative energies are what they say: GGX's at alpha 1 is the
// cosine lobe's (D = 1 / pi), closed form 1 - cos^2 (within the sum's
// step: a cut mid-step misplaces at most half a 0.075 degree step of a
// density under 1 per radian, 7e-4); a narrow GGX lobe holds almost all
// its energy within a few degrees, a wide one does not.
TEST(MetallicRoughness, LobeEnergiesAreTheLobesOwn) {
  for (const double degrees : {5.0, 20.0, 45.0, 70.0}) {
    const double theta = degrees * M_PI / 180.0;
    EXPECT_NEAR(ggxLobeEnergyWithin(1.0, theta), 1.0 - std::cos(theta) * std::cos(theta), 7e-4) << degrees;
    EXPECT_NEAR(phongLobeEnergyWithin(1.0, theta), 1.0 - std::cos(theta) * std::cos(theta), 1e-12) << degrees;
  }
  EXPECT_GT(ggxLobeEnergyWithin(0.0025, 2.0 * M_PI / 180.0), 0.95);
  EXPECT_LT(ggxLobeEnergyWithin(0.3, 10.0 * M_PI / 180.0), 0.2);
  EXPECT_NEAR(ggxLobeEnergyWithin(0.09, 0.5 * M_PI), 1.0, 1e-12);
}

// Each rung's alpha is the GGX lobe its map's lobe matches best: the fit's
// error is least there (against 10% either side), and below the error of
// the Beckmann-Phong peak equivalence, 1 / sqrt(2 n + 1), which ignores
// GGX's tail. The diffuse map is alpha 1 exactly; increasing.
TEST(MetallicRoughness, RungAlphasAreTheGgxLobesTheMapsMatchBest) {
  const std::vector<double> alphas = specularRungAlphas(kDefaultExponents);
  ASSERT_EQ(alphas.size(), 4u);
  EXPECT_EQ(alphas[0], 0.0);
  EXPECT_EQ(alphas[3], 1.0);
  EXPECT_NEAR(ggxAlphaOfPhongExponent(1.0), 1.0, 1e-3) << "the fit finds the cosine lobe's alpha too";
  for (std::size_t k = 1; k < 3; ++k) {
    const double n = kDefaultExponents[k - 1];
    const double best = lobeFitError(alphas[k], n);
    EXPECT_LT(best, lobeFitError(0.9 * alphas[k], n)) << n;
    EXPECT_LT(best, lobeFitError(1.1 * alphas[k], n)) << n;
    EXPECT_LT(best, 0.5 * lobeFitError(1.0 / std::sqrt(2.0 * n + 1.0), n)) << n;
    EXPECT_GT(alphas[k], alphas[k - 1]);
  }
  EXPECT_NEAR(alphas[1], 0.046, 0.002);
  EXPECT_NEAR(alphas[2], 0.146, 0.004);
}

TEST(MetallicRoughness, ARoughnessReadsTheTwoRungsThatBracketItsAlpha) {
  const std::vector<double> alphas = specularRungAlphas(kDefaultExponents);
  // Roughness 0 is the mirror alone, and a rung's own alpha is that rung alone.
  EXPECT_EQ(specularLadderBlend(0.0f, alphas).lower, 0);
  EXPECT_EQ(specularLadderBlend(0.0f, alphas).toward_next, 0.0f);
  for (int k = 1; k < 4; ++k) {
    const auto roughness = static_cast<float>(std::sqrt(alphas[static_cast<size_t>(k)]));
    const ReflectionLadderBlend blend = specularLadderBlend(roughness, alphas);
    EXPECT_NEAR(blend.lower + blend.toward_next, k, 1e-5) << k;
  }
  // Rougher than the diffuse rung: the diffuse map alone; NaN is glTF's default 1.
  EXPECT_EQ(specularLadderBlend(1.0f, alphas).lower, 3);
  EXPECT_EQ(specularLadderBlend(std::numeric_limits<float>::quiet_NaN(), alphas).lower, 3);
  // Roughness 0.3 (alpha 0.09) lies between glossy 0 (0.046) and glossy 1 (0.146), linearly in alpha.
  const ReflectionLadderBlend middle = specularLadderBlend(0.3f, alphas);
  EXPECT_EQ(middle.lower, 1);
  EXPECT_NEAR(middle.toward_next, (0.09 - alphas[1]) / (alphas[2] - alphas[1]), 1e-5);
  // The position never decreases with roughness.
  float previous = -1.0f;
  for (int i = 0; i <= 100; ++i) {
    const ReflectionLadderBlend blend = specularLadderBlend(i / 100.0f, alphas);
    EXPECT_GE(blend.lower + blend.toward_next, previous);
    previous = blend.lower + blend.toward_next;
  }
  // Without glossy maps the ladder is mirror then diffuse.
  const std::vector<double> bare = specularRungAlphas({});
  EXPECT_EQ(specularLadderBlend(0.3f, bare).lower, 0);
  EXPECT_GT(specularLadderBlend(0.3f, bare).toward_next, 0.0f);
}

TEST(MetallicRoughness, RungRangeCoversEveryRoughnessBetweenItsEnds) {
  const std::vector<double> alphas = specularRungAlphas(kDefaultExponents);
  EXPECT_EQ(specularRungRange(1.0f, 1.0f, alphas).first, 3);
  EXPECT_EQ(specularRungRange(1.0f, 1.0f, alphas).last, 3);
  EXPECT_EQ(specularRungRange(0.0f, 0.0f, alphas).last, 0);
  const RungRange wide = specularRungRange(0.05f, 0.9f, alphas);
  EXPECT_EQ(wide.first, 0);
  EXPECT_EQ(wide.last, 3);
  for (int i = 0; i <= 20; ++i) {
    const float lo = i / 20.0f;
    for (int j = i; j <= 20; ++j) {
      const float hi = j / 20.0f;
      const RungRange range = specularRungRange(lo, hi, alphas);
      for (const float r : {lo, 0.5f * (lo + hi), hi}) {
        const ReflectionLadderBlend blend = specularLadderBlend(r, alphas);
        EXPECT_GE(blend.lower, range.first);
        EXPECT_LE(blend.lower + (blend.toward_next > 0.0f ? 1 : 0), range.last);
      }
    }
  }
}

// A uniform environment of radiance L: every rung reads L, so a white
// dielectric returns exactly L (what the specular takes the diffuse gives
// back), a metal of base colour b returns L (b scale + bias), and occlusion
// and emission act as stated.
TEST(MetallicRoughness, AUniformEnvironmentConservesWhatTheSplitSumReflects) {
  const int face = 8;
  CubeMapRGB uniform_map(face);
  const glm::vec3 radiance(0.6f, 0.5f, 0.4f);
  for (auto& face_texels : uniform_map.faces)
    for (auto& texel : face_texels) texel = radiance;
  const std::vector<const CubeMapRGB*> glossy{&uniform_map, &uniform_map};
  const std::vector<double> alphas = specularRungAlphas(kDefaultExponents);
  const EnvironmentBrdfTable table;
  const SceneLighting lighting;
  const glm::vec3 n(0, 0, 1);
  for (const float roughness : {0.05f, 0.3f, 0.6f, 1.0f})
    for (const float cos_view : {1.0f, 0.5f, 0.15f}) {
      const glm::vec3 v(std::sqrt(1.0f - cos_view * cos_view), 0.0f, cos_view);
      MetallicRoughnessSurface white;
      white.base_color = glm::vec3(1.0f);
      white.metallic = 0.0f;
      white.roughness = roughness;
      const glm::vec3 dielectric =
          shadeMetallicRoughness(n, v, white, uniform_map, uniform_map, glossy, alphas, table, lighting);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(dielectric[c], radiance[c], 1e-5f);
      MetallicRoughnessSurface gold = white;
      gold.base_color = {1.0f, 0.77f, 0.34f};
      gold.metallic = 1.0f;
      const EnvironmentBrdf brdf = table.lookup(roughness, cos_view);
      const glm::vec3 metal = shadeMetallicRoughness(n, v, gold, uniform_map, uniform_map, glossy, alphas, table, lighting);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(metal[c], radiance[c] * (gold.base_color[c] * brdf.scale + brdf.bias), 1e-5f);
      gold.occlusion = 0.25f;
      gold.emissive = {0.1f, 0.0f, 0.0f};
      const glm::vec3 occluded =
          shadeMetallicRoughness(n, v, gold, uniform_map, uniform_map, glossy, alphas, table, lighting);
      EXPECT_NEAR(occluded.r, 0.25f * metal.r + 0.1f, 1e-5f);
      EXPECT_NEAR(occluded.g, 0.25f * metal.g, 1e-5f);
    }
}

}  // namespace
}  // namespace probelight::ibl
