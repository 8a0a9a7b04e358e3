// The simulator's glTF metallic-roughness BRDF (sim/gltf_brdf.hpp): the
// spec's formulas against their symmetries and energy bounds, its
// importance sampling against the test's own quadrature, and the material's
// texture lookup against the decoded texels of a corpus model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/math_constants.hpp"
#include "model/gltf_loader.hpp"
#include "model/model_placement.hpp"
#include "sim/gltf_brdf.hpp"
#include "sim/triangle_bvh.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

const glm::dvec3 kNormal(0.0, 0.0, 1.0);

GltfSurface surface(glm::dvec3 base, double metallic, double roughness) {
  GltfSurface s;
  s.base_color = base;
  s.metallic = metallic;
  s.roughness = roughness;
  return s;
}
GltfSurface whiteDielectric(double roughness) { return surface(glm::dvec3(1.0), 0.0, roughness); }
GltfSurface whiteMetal(double roughness) { return surface(glm::dvec3(1.0), 1.0, roughness); }
// Gold's F0 (linear sRGB, as the glTF sample models use it).
GltfSurface gold(double roughness) { return surface({1.0, 0.766, 0.336}, 1.0, roughness); }
GltfSurface halfMetal(double roughness) { return surface({0.3, 0.6, 0.9}, 0.5, roughness); }

glm::dvec3 viewAt(double theta_rad) { return {std::sin(theta_rad), 0.0, std::cos(theta_rad)}; }

// The test's own integral over the whole sphere of directions: the midpoint
// rule on a grid in (s, phi), s in [0, 1], with the angle from `pole`
// theta = pi s^2 (so dw = sin(theta) 2 pi s ds dphi). Cells shrink as s^2
// towards the pole: put it on the specular peak (the mirror direction) and
// a GGX lobe of roughness 0.05 (alpha 0.0025, about 5 mrad wide in l) spans
// some 20 cells of the 1024 in s, where a uniform grid of the same size
// would give it one. The integrands are continuous (n.l takes them to 0 at
// the horizon), so the rule converges as h^2 away from the horizon's kink.
template <typename F>
auto sphereIntegral(const glm::dvec3& pole, F&& g, int ns = 1024, int nphi = 512) {
  const glm::dvec3 helper = std::abs(pole.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
  const glm::dvec3 t = glm::normalize(glm::cross(helper, pole)), b = glm::cross(pole, t);
  decltype(g(pole)) sum{0.0};
  for (int i = 0; i < ns; ++i) {
    const double s = (i + 0.5) / ns, theta = kPi * s * s;
    const double weight = std::sin(theta) * 2.0 * kPi * s * (1.0 / ns) * (2.0 * kPi / nphi);
    const double st = std::sin(theta), ct = std::cos(theta);
    for (int j = 0; j < nphi; ++j) {
      const double phi = (j + 0.5) * 2.0 * kPi / nphi;
      const glm::dvec3 l = st * std::cos(phi) * t + st * std::sin(phi) * b + ct * pole;
      sum += weight * g(l);
    }
  }
  return sum;
}

glm::dvec3 mirror(const glm::dvec3& v) { return 2.0 * glm::dot(kNormal, v) * kNormal - v; }

// The directional albedo, integral of f (n.l) over l, by quadrature.
using gltf_brdf::SmithVisibility;
constexpr SmithVisibility kBothForms[] = {SmithVisibility::kSeparable, SmithVisibility::kHeightCorrelated};

glm::dvec3 albedoByQuadrature(const glm::dvec3& v, const GltfSurface& s,
                              SmithVisibility form = SmithVisibility::kSeparable) {
  return sphereIntegral(mirror(v), [&](const glm::dvec3& l) { return gltf_brdf::evaluate(kNormal, v, l, s, form); });
}

struct Estimate {
  glm::dvec3 mean{0.0}, standard_error{0.0};
};
// The same integral by importance sampling: mean of evaluate / pdf.
Estimate albedoBySampling(const glm::dvec3& v, const GltfSurface& s, SmithVisibility form, int samples,
                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  glm::dvec3 sum(0.0), sum_squares(0.0);
  for (int i = 0; i < samples; ++i) {
    const double u1 = u(rng), u2 = u(rng), u3 = u(rng);
    const gltf_brdf::BrdfSample sample = gltf_brdf::sampleDirection(kNormal, v, s, u1, u2, u3);
    glm::dvec3 w(0.0);
    if (sample.pdf > 0.0) w = gltf_brdf::evaluate(kNormal, v, sample.l, s, form) / sample.pdf;
    sum += w;
    sum_squares += w * w;
  }
  Estimate e;
  e.mean = sum / double(samples);
  e.standard_error = glm::sqrt(glm::max(sum_squares / double(samples) - e.mean * e.mean, 0.0) / double(samples));
  return e;
}

// f(v, l) = f(l, v): D, V and |v.h| = |l.h| are symmetric, and so is the
// Lambertian term. evaluate() carries n.l, so divide it out; what is left
// differs only by rounding: 1e-12 relative.
TEST(GltfBrdf, IsReciprocal) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const GltfSurface s = surface({u(rng), u(rng), u(rng)}, u(rng), u(rng));
    auto upper = [&] {
      const double z = u(rng), phi = 2.0 * kPi * u(rng), r = std::sqrt(1.0 - z * z);
      return glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    const glm::dvec3 v = upper(), l = upper();
    if (v.z < 1e-3 || l.z < 1e-3) continue;
    for (SmithVisibility form : kBothForms) {
      const glm::dvec3 forward = gltf_brdf::evaluate(kNormal, v, l, s, form) / l.z;
      const glm::dvec3 backward = gltf_brdf::evaluate(kNormal, l, v, s, form) / v.z;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(forward[c], backward[c], 1e-12 * std::max(1.0, forward[c]));
    }
    ++checked;
  }
  EXPECT_GT(checked, 19000);
}

TEST(GltfBrdf, IsZeroBelowTheHorizonAndFiniteEverywhere) {
  const GltfSurface s = halfMetal(0.5);
  EXPECT_EQ(gltf_brdf::evaluate(kNormal, viewAt(30 * kRadPerDeg), {0.1, 0.0, -0.99}, s), glm::dvec3(0.0));
  EXPECT_EQ(gltf_brdf::evaluate(kNormal, {0.0, 0.6, -0.8}, viewAt(30 * kRadPerDeg), s), glm::dvec3(0.0));
  EXPECT_EQ(gltf_brdf::pdf(kNormal, {0.0, 0.6, -0.8}, kNormal, s), 0.0);
  EXPECT_EQ(gltf_brdf::sampleDirection(kNormal, {0.0, 0.6, -0.8}, s, 0.3, 0.3, 0.3).pdf, 0.0);
}

// Roughness 0 (clamped to alpha 1e-3) and grazing views: the mirror
// direction's value, every sample and its weight stay finite.
TEST(GltfBrdf, SmoothSurfacesStayFinite) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (double roughness : {0.0, 1e-6, 1e-3, 0.01}) {
    for (double theta_deg : {0.0, 45.0, 89.0, 89.9999}) {
      const glm::dvec3 v = viewAt(theta_deg * kRadPerDeg);
      for (const GltfSurface& s : {whiteDielectric(roughness), gold(roughness), halfMetal(roughness)}) {
        const glm::dvec3 at_mirror = gltf_brdf::evaluate(kNormal, v, mirror(v), s);
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(at_mirror[c]));
        EXPECT_GT(at_mirror.x, 0.0);
        for (int i = 0; i < 2000; ++i) {
          const gltf_brdf::BrdfSample sample = gltf_brdf::sampleDirection(kNormal, v, s, u(rng), u(rng), u(rng));
          ASSERT_TRUE(std::isfinite(sample.pdf) && sample.pdf >= 0.0);
          ASSERT_NEAR(glm::length(sample.l), 1.0, 1e-12);
          if (sample.pdf == 0.0) continue;
          const glm::dvec3 w = gltf_brdf::evaluate(kNormal, v, sample.l, s) / sample.pdf;
          for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(w[c])) << roughness << " " << theta_deg;
        }
      }
    }
  }
}

// The pdf is a density over the whole sphere: it integrates to 1. The
// quadrature's error is below 1e-4 for these lobes (doubling the grid
// changes the result by less than that); 1e-3 leaves margin.
TEST(GltfBrdf, PdfIntegratesToOne) {
  for (double roughness : {0.05, 0.3, 0.7, 1.0})
    for (double theta_deg : {0.0, 40.0, 75.0})
      for (const GltfSurface& s : {whiteDielectric(roughness), gold(roughness)}) {
        const glm::dvec3 v = viewAt(theta_deg * kRadPerDeg);
        const double total =
            sphereIntegral(mirror(v), [&](const glm::dvec3& l) { return gltf_brdf::pdf(kNormal, v, l, s); });
        EXPECT_NEAR(total, 1.0, 1e-3) << "roughness " << roughness << ", view " << theta_deg << " deg";
      }
}

// The importance-sampled estimate of the directional albedo against the
// quadrature, for smooth to rough surfaces, facing to grazing views, a
// dielectric, a metal and a half-metal. 2^17 samples give a standard error
// below 3e-3 of the albedo (0.28% at worst: the rough metals); the two may
// differ by 5 standard errors (1 in 1.7 million for a normal error) plus the
// quadrature's error (below 1e-4 up to 75 deg: doubling the grid changes
// the result by 4e-5 at most): a sampler whose density is not the pdf it
// reports is off by far more. The height-correlated form on a few cases:
// the sampler is the same, the integrand not.
TEST(GltfBrdf, ImportanceSamplingMatchesQuadrature) {
  std::uint64_t seed = 10;
  auto check = [&](const GltfSurface& s, double roughness, double theta_deg, SmithVisibility form) {
    const glm::dvec3 v = viewAt(theta_deg * kRadPerDeg);
    const glm::dvec3 quadrature = albedoByQuadrature(v, s, form);
    const Estimate sampled = albedoBySampling(v, s, form, 1 << 17, ++seed);
    for (int c = 0; c < 3; ++c) {
      EXPECT_LT(sampled.standard_error[c], 4e-3 * quadrature[c] + 1e-4) << "too noisy to tell";
      EXPECT_NEAR(sampled.mean[c], quadrature[c], 5.0 * sampled.standard_error[c] + 1e-4)
          << "roughness " << roughness << ", view " << theta_deg << " deg, metallic " << s.metallic << ", channel "
          << c << (form == SmithVisibility::kSeparable ? "" : ", height-correlated");
    }
  };
  for (double roughness : {0.05, 0.3, 1.0})
    for (double theta_deg : {0.0, 45.0, 75.0})
      for (const GltfSurface& s : {whiteDielectric(roughness), gold(roughness), halfMetal(roughness)})
        check(s, roughness, theta_deg, SmithVisibility::kSeparable);
  for (double roughness : {0.05, 0.3, 1.0}) check(gold(roughness), roughness, 75.0, SmithVisibility::kHeightCorrelated);
}

// White furnace: a white metal sends back at most what it receives, at any
// roughness and view, in either Smith form (single-scattering GGX loses the
// light that bounces between microfacets: 69% at roughness 1 facing it).
// Quadrature, good to 1e-4 up to 75 deg (see above), and to 1e-3 at 89 deg.
TEST(GltfBrdf, WhiteFurnaceMetalsSendBackAtMostWhatComesIn) {
  for (SmithVisibility form : kBothForms)
    for (double theta_deg : {0.0, 30.0, 60.0, 75.0, 89.0})
      for (double roughness : {0.05, 0.3, 0.6, 1.0})
        EXPECT_LE(albedoByQuadrature(viewAt(theta_deg * kRadPerDeg), whiteMetal(roughness), form).x, 1.0 + 1e-3)
            << "roughness " << roughness << ", view " << theta_deg << " deg";
  // Roughness 1 (alpha 1) facing the surface has a closed form: D = 1/pi,
  // V = 1 / (2 (1 + mu)) in both forms, F = 1, so the albedo is
  // 2 pi integral of mu / (2 pi (1 + mu)) dmu over [0, 1] = 1 - ln 2.
  for (SmithVisibility form : kBothForms)
    EXPECT_NEAR(albedoByQuadrature(viewAt(0.0), whiteMetal(1.0), form).x, 1.0 - std::log(2.0), 1e-5);
}

// The Lambertian limit: a white dielectric. Facing it and at moderate
// angles it sends back at most what comes in: the diffuse loses (1 - F) to
// the specular layer, F0 = 0.04, and gets it back only in part. At roughness
// 1 facing it, the albedo is a 1D integral the test does by Simpson's rule
// (h = pi / 4000, error ~1e-12): with h = (n + l) / |n + l|, v.h = cos(theta
// / 2), D = 1/pi, V = 1 / (2 (1 + cos theta)),
//   E = 2 pi integral over theta of [(1 - F) / pi + F / (2 pi (1 + cos theta))] cos theta sin theta,
// and it is within 3% of 1. At grazing views the spec's fresnel_mix is not
// energy conserving (the header says why): the oracle follows the spec, so a
// change to an energy-conserving mix must show up here.
TEST(GltfBrdf, WhiteFurnaceDielectricIsTheSpecsLambertianLimit) {
  for (double theta_deg : {0.0, 30.0})
    for (double roughness : {0.05, 0.3, 0.6, 1.0})
      for (SmithVisibility form : kBothForms)
        EXPECT_LE(albedoByQuadrature(viewAt(theta_deg * kRadPerDeg), whiteDielectric(roughness), form).x, 1.0 + 1e-4)
            << "roughness " << roughness << ", view " << theta_deg << " deg";
  auto integrand = [](double theta) {
    const double f = 0.04 + 0.96 * std::pow(1.0 - std::cos(theta / 2.0), 5.0);
    return 2.0 * kPi * ((1.0 - f) / kPi + f / (2.0 * kPi * (1.0 + std::cos(theta)))) * std::cos(theta) *
           std::sin(theta);
  };
  const int intervals = 2000;
  const double h = (kPi / 2.0) / intervals;
  double simpson = integrand(0.0) + integrand(kPi / 2.0);
  for (int i = 1; i < intervals; ++i) simpson += (i % 2 ? 4.0 : 2.0) * integrand(i * h);
  simpson *= h / 3.0;
  const double facing = albedoByQuadrature(viewAt(0.0), whiteDielectric(1.0)).x;
  EXPECT_NEAR(facing, simpson, 1e-5);
  EXPECT_GT(facing, 0.97);
  EXPECT_LT(facing, 1.0);
  // Grazing, smooth: more out than in (1.2 at 75 deg), as the spec's mix has it.
  EXPECT_GT(albedoByQuadrature(viewAt(75.0 * kRadPerDeg), whiteDielectric(0.05)).x, 1.15);
}

// ---- Texture lookup, on the corpus's textured box ----

const std::string kBoxFile = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";

const model::MeshModel& texturedBox() {
  static const model::MeshModel box = [] {
    model::MeshModel m;
    std::string error;
    EXPECT_TRUE(model::loadGltfModel(kBoxFile, {}, m, error)) << error;
    return m;
  }();
  return box;
}

glm::dvec3 decodedTexel(const model::TextureImage& image, int x, int y) {
  const std::uint8_t* p = &image.rgba[(static_cast<std::size_t>(y) * image.width + x) * 4];
  return {testing::srgbDecode(p[0]), testing::srgbDecode(p[1]), testing::srgbDecode(p[2])};
}

TriangleHit hitAt(glm::dvec2 uv0, int material = 0) {
  TriangleHit hit;
  hit.uv0 = uv0;
  hit.uv1 = glm::dvec2(0.0);
  hit.material = material;
  return hit;
}

// At a texel's centre the bilinear weights are 1 and 0 (to the rounding of
// (x + 0.5) / W * W - 0.5, ~1e-13): the base colour is that texel, sRGB
// decoded (the test's own decode), times the factor 1. 1e-9.
TEST(GltfBrdf, BaseColourAtATexelCentreIsTheDecodedTexel) {
  const model::MeshModel& box = texturedBox();
  ASSERT_EQ(box.materials.size(), 1u);
  const model::Material& material = box.materials[0];
  ASSERT_TRUE(material.base_color.present());
  const model::TextureImage& image = box.images[static_cast<std::size_t>(material.base_color.image)];
  ASSERT_EQ(image.width, 211);
  ASSERT_EQ(image.height, 211);
  int differing = 0;
  for (int y = 0; y < image.height; y += 7)
    for (int x = 0; x < image.width; x += 5) {
      const glm::dvec2 uv((x + 0.5) / image.width, (y + 0.5) / image.height);
      const GltfSurface s = surfaceAt(box, hitAt(uv));
      const glm::dvec3 expected = decodedTexel(image, x, y);
      EXPECT_NEAR(glm::length(s.base_color - expected), 0.0, 1e-9) << x << ", " << y;
      differing += glm::length(expected - decodedTexel(image, 0, 0)) > 0.05;
      EXPECT_EQ(s.metallic, 0.0);  // metallicFactor 0
      EXPECT_EQ(s.roughness, 1.0);
      EXPECT_EQ(s.alpha, 1.0);
      EXPECT_EQ(s.emissive, glm::dvec3(0.0));
    }
  EXPECT_GT(differing, 100) << "a texture with something on it";
  // Half-way between two texel centres: the mean of the decoded texels, not
  // the decode of the mean code (a GPU's sRGB texture filters linear values).
  for (int x = 20; x < 200; x += 17) {
    const glm::dvec2 uv((x + 1.0) / image.width, (100 + 0.5) / image.height);
    const glm::dvec3 expected = 0.5 * (decodedTexel(image, x, 100) + decodedTexel(image, x + 1, 100));
    EXPECT_NEAR(glm::length(surfaceAt(box, hitAt(uv)).base_color - expected), 0.0, 1e-9) << x;
  }
}

// The box's sampler: wrapS MIRRORED_REPEAT, wrapT CLAMP_TO_EDGE. Mirrored:
// u and -u, 2 - u and u + 2 read the same texels; clamped: any v past the
// last texel centre reads the edge row. REPEAT (the slot changed here): u
// and u + 1. Each pair reads the same texels with the same weights, to
// rounding: 1e-9.
TEST(GltfBrdf, WrapModesBehaveAsGl) {
  const model::MeshModel& box = texturedBox();
  const model::TextureSlot& slot = box.materials[0].base_color;
  ASSERT_EQ(slot.wrap_s, model::TextureWrap::kMirroredRepeat);
  ASSERT_EQ(slot.wrap_t, model::TextureWrap::kClampToEdge);
  const model::TextureImage& image = box.images[static_cast<std::size_t>(slot.image)];
  auto at = [&](const model::TextureSlot& sl, double u, double v) {
    return glm::dvec3(sampleTexture(image, sl, {u, v}, TexelEncoding::kSrgb));
  };
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double edge = 0.5 / image.height;
  model::TextureSlot repeat = slot;
  repeat.wrap_s = repeat.wrap_t = model::TextureWrap::kRepeat;
  int mirror_differs_from_repeat = 0;
  for (int i = 0; i < 2000; ++i) {
    const double u = unit(rng), v = unit(rng);
    const glm::dvec3 here = at(slot, u, v);
    EXPECT_NEAR(glm::length(at(slot, -u, v) - here), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(at(slot, 2.0 - u, v) - here), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(at(slot, u + 2.0, v) - here), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(at(slot, u, 1.0 + v) - at(slot, u, 1.0 - edge)), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(at(slot, u, -v) - at(slot, u, edge)), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(at(repeat, u + 1.0, v) - at(repeat, u, v)), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(at(repeat, u, v - 3.0) - at(repeat, u, v)), 0.0, 1e-9);
    mirror_differs_from_repeat += glm::length(at(repeat, u + 1.0, v) - at(slot, u + 1.0, v)) > 0.01;
  }
  EXPECT_GT(mirror_differs_from_repeat, 200);
  // The mesh's own UVs run to 6 in u: the texture mirrored three times over.
  EXPECT_NEAR(glm::length(at(slot, 5.25, 0.5) - at(slot, 0.75, 0.5)), 0.0, 1e-9);
  // Far out and non-finite coordinates read some texel, never out of bounds.
  for (double far : {1e12, -1e15, 1e300, std::numeric_limits<double>::infinity(),
                     std::numeric_limits<double>::quiet_NaN()}) {
    const glm::dvec3 c = at(slot, far, far);
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(c[k] >= 0.0 && c[k] <= 1.0);
  }
  // NEAREST: the texel the point falls in, whole.
  model::TextureSlot nearest = slot;
  nearest.nearest = true;
  EXPECT_NEAR(glm::length(at(nearest, (30 + 0.9) / image.width, (40 + 0.1) / image.height) -
                          decodedTexel(image, 30, 40)),
              0.0, 1e-12);
}

// KHR_texture_transform's worked example: offset (0, 1), rotation pi/2,
// scale 0.5 shows the lower-left quadrant: the unit square's corners land
// on (0, 1), (0, 0.5), (0.5, 1), (0.5, 0.5). Double maths on float inputs
// (pi/2 as a float): 1e-7.
TEST(GltfBrdf, TextureTransformIsTheExtensionsExample) {
  model::TextureSlot slot;
  slot.uv_offset = {0.0f, 1.0f};
  slot.uv_rotation_rad = static_cast<float>(kPi / 2);
  slot.uv_scale = {0.5f, 0.5f};
  const std::pair<glm::dvec2, glm::dvec2> corners[] = {
      {{0, 0}, {0, 1}}, {{1, 0}, {0, 0.5}}, {{0, 1}, {0.5, 1}}, {{1, 1}, {0.5, 0.5}}};
  for (const auto& [uv, expected] : corners)
    EXPECT_NEAR(glm::length(textureTransform(slot, uv) - expected), 0.0, 1e-7) << uv.x << ", " << uv.y;
  // And the lookup goes through it: the transformed slot at uv reads what
  // the plain one reads at the transformed uv.
  const model::MeshModel& box = texturedBox();
  model::TextureSlot plain = box.materials[0].base_color, moved = plain;
  moved.uv_offset = slot.uv_offset;
  moved.uv_rotation_rad = slot.uv_rotation_rad;
  moved.uv_scale = slot.uv_scale;
  const model::TextureImage& image = box.images[static_cast<std::size_t>(plain.image)];
  for (const glm::dvec2 uv : {glm::dvec2(0.3, 0.6), glm::dvec2(0.8, 0.1)}) {
    const glm::dvec4 through = sampleTexture(image, moved, uv, TexelEncoding::kSrgb);
    const glm::dvec4 direct = sampleTexture(image, plain, textureTransform(slot, uv), TexelEncoding::kSrgb);
    EXPECT_NEAR(glm::length(through - direct), 0.0, 1e-12);
  }
}

// A made-up material on the box: factors times textures times the vertex
// colour, each texture read through the UV set its slot names, the
// metallic-roughness texture linear (G roughness, B metallic), the emissive
// sRGB. Exact maths on 8-bit codes: 1e-12.
TEST(GltfBrdf, SurfaceCombinesFactorsTexturesAndVertexColour) {
  model::MeshModel m = texturedBox();
  model::TextureImage channels;
  channels.width = channels.height = 2;
  // RGBA, rows top first: (255, 51, 204, 255) at the top-left texel.
  channels.rgba = {255, 51, 204, 255, 0, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 255};
  m.images.push_back(channels);
  const int channels_image = static_cast<int>(m.images.size() - 1);
  model::Material& material = m.materials[0];
  material.base_color_factor = {0.5f, 1.0f, 0.25f, 0.8f};
  material.base_color.texcoord = 1;
  material.metallic_factor = 0.5f;
  material.roughness_factor = 0.75f;
  material.metallic_roughness.image = channels_image;
  material.metallic_roughness.wrap_s = material.metallic_roughness.wrap_t = model::TextureWrap::kClampToEdge;
  material.emissive_factor = {2.0f, 1.0f, 0.5f};
  material.emissive.image = channels_image;
  material.emissive.wrap_s = material.emissive.wrap_t = model::TextureWrap::kClampToEdge;

  const model::TextureImage& logo = m.images[static_cast<std::size_t>(material.base_color.image)];
  TriangleHit hit;
  hit.material = 0;
  hit.uv0 = {0.25, 0.25};                                            // the channels' top-left texel centre
  hit.uv1 = {(60 + 0.5) / logo.width, (70 + 0.5) / logo.height};     // a logo texel centre
  hit.color = {0.5, 0.5, 1.0, 0.5};
  const GltfSurface s = surfaceAt(m, hit);
  const glm::dvec3 texel = decodedTexel(logo, 60, 70);
  EXPECT_NEAR(glm::length(s.base_color - glm::dvec3(0.5, 1.0, 0.25) * texel * glm::dvec3(0.5, 0.5, 1.0)), 0.0, 1e-9);
  EXPECT_NEAR(s.alpha, 0.8 * 1.0 * 0.5, 1e-7);
  EXPECT_NEAR(s.roughness, 0.75 * 51.0 / 255.0, 1e-12);
  EXPECT_NEAR(s.metallic, 0.5 * 204.0 / 255.0, 1e-12);
  const glm::dvec3 emissive_texel(1.0, testing::srgbDecode(51), testing::srgbDecode(204));
  EXPECT_NEAR(glm::length(s.emissive - glm::dvec3(2.0, 1.0, 0.5) * emissive_texel), 0.0, 1e-12);

  // No material: glTF's default, white, metallic 1, roughness 1.
  const GltfSurface plain = surfaceAt(m, hitAt({0.5, 0.5}, -1));
  EXPECT_EQ(plain.base_color, glm::dvec3(1.0));
  EXPECT_EQ(plain.metallic, 1.0);
  EXPECT_EQ(plain.roughness, 1.0);
}

// A ray on the placed box and the texture: the hit's UVs are the face's
// (0 to 6 in u, 0 to 1 in v), and its surface is the texture there.
TEST(GltfBrdf, RayHitOnTheBoxReadsItsTexture) {
  const model::MeshModel& box = texturedBox();
  model::ModelPlacement placement;
  placement.scale = 0.2;
  const TriangleScene scene(box, model::worldFromModel(box, placement));
  const model::TextureSlot& slot = box.materials[0].base_color;
  const model::TextureImage& image = box.images[static_cast<std::size_t>(slot.image)];
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-0.09, 0.09);
  for (int i = 0; i < 200; ++i) {
    const std::optional<TriangleHit> hit = scene.intersect({u(rng), u(rng), 1.0}, {0.0, 0.0, -1.0}, 10.0);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->t, 0.8, 1e-12);
    EXPECT_TRUE(hit->uv0.x >= 0.0 && hit->uv0.x <= 6.0 && hit->uv0.y >= 0.0 && hit->uv0.y <= 1.0);
    const glm::dvec3 expected(sampleTexture(image, slot, hit->uv0, TexelEncoding::kSrgb));
    EXPECT_NEAR(glm::length(surfaceAt(box, *hit).base_color - expected), 0.0, 1e-12);
  }
}

}  // namespace
}  // namespace probelight::sim
