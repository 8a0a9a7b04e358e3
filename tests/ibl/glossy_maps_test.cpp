// ibl::glossyMap: the reflection map convolved with a normalised cos^n lobe
// by two separable passes (derivation in src/ibl/glossy_maps.hpp).
#include "ibl/glossy_maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>

#include "ibl/spherical_blur.hpp"
#include "ibl/surface_shading.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

using Radiance = std::function<glm::dvec3(const glm::dvec3&)>;

CubeMapRGB cubeFrom(int face_size, const Radiance& radiance) {
  CubeMapRGB cube(face_size);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < face_size; ++y)
      for (int x = 0; x < face_size; ++x)
        cube.texel(face, x, y) = glm::vec3(radiance(cubeTexelCenterDirection(face, x, y, face_size)));
  return cube;
}

glm::dvec3 smoothSky(const glm::dvec3& d) {
  const double window = std::pow(std::max(0.0, glm::dot(d, glm::normalize(glm::dvec3(0.6, 0.3, 0.74)))), 6.0);
  return {0.10 + 0.25 * (0.5 + 0.5 * d.z) + 0.55 * window, 0.18 + 0.12 * (0.5 + 0.5 * d.x) + 0.35 * window,
          0.22 + 0.18 * (0.5 + 0.5 * d.y) + 0.15 * window};
}

// A uniform disc lamp of angular radius `radius_rad` around `axis`.
Radiance lamp(const glm::dvec3& axis, double radius_rad, double gain, const Radiance& background) {
  return [=](const glm::dvec3& d) {
    return background(d) + (glm::dot(d, axis) > std::cos(radius_rad) ? glm::dvec3(gain) : glm::dvec3(0.0));
  };
}

// sum_t L_t cos^n(r.d_t)+ Omega_t / sum_t cos^n(r.d_t)+ Omega_t over the
// input's texels: the lobe's mean radiance, by brute force.
glm::dvec3 bruteForceLobe(const CubeMapRGB& input, double exponent, const glm::dvec3& r) {
  glm::dvec3 sum(0.0);
  double weight_sum = 0.0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < input.face_size; ++y)
      for (int x = 0; x < input.face_size; ++x) {
        const double c = glm::dot(r, cubeTexelCenterDirection(face, x, y, input.face_size));
        if (c <= 0.0) continue;
        const double w = std::pow(c, exponent) * cubeTexelSolidAngle(x, y, input.face_size);
        sum += w * glm::dvec3(input.texel(face, x, y));
        weight_sum += w;
      }
  return sum / weight_sum;
}

struct Moments {
  double energy = 0.0;       // sum L Omega (red channel)
  double mean_cosine = 0.0;  // sum L (axis.d) Omega / energy
};

Moments moments(const CubeMapRGB& cube, const glm::dvec3& axis) {
  Moments m;
  double weighted = 0.0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < cube.face_size; ++y)
      for (int x = 0; x < cube.face_size; ++x) {
        const double e = cube.texel(face, x, y).r * cubeTexelSolidAngle(x, y, cube.face_size);
        m.energy += e;
        weighted += e * glm::dot(axis, cubeTexelCenterDirection(face, x, y, cube.face_size));
      }
  m.mean_cosine = weighted / m.energy;
  return m;
}

TEST(GlossyMaps, DefaultsAndSeriesKernel) {
  for (int level : {0, 1}) {
    const GlossyLevelSettings s = defaultGlossyLevel(level);
    EXPECT_EQ(64 % s.prefilter_face_size, 0);
    // The series kernel against cos^m at every tap: the truncated terms are
    // positive, so the series is below -ln cos by < 691 a^12 / 467775 + ...
    double worst = 0.0;
    for (int i = -s.half_taps; i <= s.half_taps; ++i) {
      const double a = glossyTapAngleRad(s.exponent, s.half_taps, i);
      for (double m : {s.exponent, s.exponent + 1.0})
        worst = std::max(worst, std::abs(glossyTapWeight(m, a) / std::pow(std::cos(a), m) - 1.0));
    }
    std::printf("[ measure  ] level %d (n = %g): series kernel vs cos^m, worst relative %.2e\n", level, s.exponent,
                worst);
    EXPECT_LT(worst, 5e-5 * (s.exponent + 1.0));
  }
}

// Weights are normalised per pass: only float rounding (2^-24 relative per
// operation, a few dozen operations) remains.
TEST(GlossyMaps, ConstantMapStaysConstant) {
  const CubeMapRGB input = cubeFrom(64, [](const glm::dvec3&) { return glm::dvec3(0.25, 0.5, 2.0); });
  for (int level : {0, 1}) {
    const CubeMapRGB out = glossyMap(input, defaultGlossyLevel(level));
    for (const auto& face : out.faces)
      for (const glm::vec3& t : face) {
        EXPECT_NEAR(t.r, 0.25f, 1e-6f);
        EXPECT_NEAR(t.g, 0.5f, 1e-6f);
        EXPECT_NEAR(t.b, 2.0f, 4e-6f);
      }
  }
}

// A small lamp on black. Energy: the normalised lobe integrates to 1 over
// the sphere, so sum G Omega = sum L Omega, up to the 3-sigma truncation of
// each axis (<= 0.27% each for a Gaussian, less for cos^n's lighter tail),
// whose lost mass is not returned where the square (a, b) window is
// anisotropic: 1% bounds it. Width (Funk-Hecke): convolving with a zonal
// kernel multiplies the mean cosine about the lamp's axis by the kernel's,
// (n + 1) / (n + 2) for cos^n. So the spread s = 1 - <cos> of the result is
// predicted from the input's own (pixelated) disc. The passes add the
// variance of their interpolations (bilinear: h^2 / 6 per axis, h the
// texel's angle, each of the prefiltered and intermediate reads; the 2x2 box
// prefilter h^2/12): with h <= 2 / face_size, s grows by at most
// (h_pre^2 / 6 + h_pre^2 / 12 + h_int^2 / 6) (1 - cos ~ angle^2 / 2 summed
// over two axes), which is the upper tolerance; truncation makes it
// narrower, by < 3% of s (lower tolerance).
//
// The lamp sits near a face centre on purpose: one within half a texel of
// a face edge gains energy (measured: +2.5% for n = 16 at 16^2), because
// the per-face bilinear lookups (ibl::CubeMapRGB::sampleBilinear, GLES2's
// non-seamless cube maps) clamp to the edge texel there, giving it full
// weight over the last half texel instead of a tent's. The diffuse map has
// the same property; it is a property of the lookups, not of the lobe.
TEST(GlossyMaps, SmallLampKeepsItsEnergyAndGetsTheLobesWidth) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(0.2, -0.1, 1.0));
  const CubeMapRGB input = cubeFrom(64, lamp(axis, 3.0 * M_PI / 180.0, 100.0, [](const glm::dvec3&) {
                                      return glm::dvec3(0.0);
                                    }));
  const Moments in = moments(input, axis);
  for (int level : {0, 1}) {
    const GlossyLevelSettings s = defaultGlossyLevel(level);
    const CubeMapRGB out = glossyMap(input, s);
    const Moments got = moments(out, axis);
    const double lobe_cosine = (s.exponent + 1.0) / (s.exponent + 2.0);
    const double expected_spread = 1.0 - lobe_cosine * in.mean_cosine;
    const double h_pre = 2.0 / s.prefilter_face_size, h_int = 2.0 / s.intermediate_face_size;
    const double interpolation_spread = h_pre * h_pre / 6.0 + h_pre * h_pre / 12.0 + h_int * h_int / 6.0;
    const double spread = 1.0 - got.mean_cosine;
    std::printf("[ measure  ] n = %g: energy ratio %.4f, spread %.5f (analytic %.5f, + interpolation <= %.5f)\n",
                s.exponent, got.energy / in.energy, spread, expected_spread, interpolation_spread);
    EXPECT_NEAR(got.energy / in.energy, 1.0, 0.01);
    EXPECT_GT(spread, 0.97 * expected_spread);
    EXPECT_LT(spread, expected_spread + interpolation_spread);
  }
}

// A lamp 5 degrees from the zenith on a smooth sky, against the brute-force
// lobe at every output texel, with and without the pole correction.
double worstRelativeError(const CubeMapRGB& input, const GlossyLevelSettings& s, const glm::dvec3& lamp_axis,
                          double* mean = nullptr) {
  const CubeMapRGB out = glossyMap(input, s);
  // Away from the lamp both are the smooth sky; compare where the lobe reaches it.
  const double reach = std::cos(5.0 / std::sqrt(s.exponent) + 0.1);
  double worst = 0.0, sum = 0.0;
  int count = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < s.output_face_size; ++y)
      for (int x = 0; x < s.output_face_size; ++x) {
        const glm::dvec3 r = cubeTexelCenterDirection(face, x, y, s.output_face_size);
        if (glm::dot(r, lamp_axis) < reach) continue;
        const glm::dvec3 want = bruteForceLobe(input, s.exponent, r);
        const double e = std::abs(out.texel(face, x, y).r - want.r) / want.r;
        worst = std::max(worst, e);
        sum += e;
        ++count;
      }
  if (mean) *mean = sum / count;
  return worst;
}

TEST(GlossyMaps, ZenithLampAgainstBruteForceWithAndWithoutPoleCorrection) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(0.08, 0.03, 1.0));
  // The same lamp on the +X face's centre (the same place on its face's
  // grid, by the cube's symmetry), where the east tangent field is regular.
  const glm::dvec3 equator_axis(axis.z, axis.y, -axis.x);
  const CubeMapRGB input = cubeFrom(64, lamp(axis, 4.0 * M_PI / 180.0, 50.0, [](const glm::dvec3&) { return glm::dvec3(0.3); }));
  const CubeMapRGB equator = cubeFrom(64, lamp(equator_axis, 4.0 * M_PI / 180.0, 50.0, [](const glm::dvec3&) { return glm::dvec3(0.3); }));
  for (int level : {0, 1}) {
    GlossyLevelSettings s = defaultGlossyLevel(level);
    double mean_with = 0.0, mean_without = 0.0, mean_equator = 0.0;
    const double at_equator = worstRelativeError(equator, s, equator_axis, &mean_equator);
    const double with = worstRelativeError(input, s, axis, &mean_with);
    const double pole_deg = s.pole_direct_deg;
    s.pole_direct_deg = 0.0;
    const double without = worstRelativeError(input, s, axis, &mean_without);
    std::printf("[ measure  ] lamp 5 deg from the zenith, n = %g: worst relative error %.2f%% with the pole "
                "correction (%g deg), %.2f%% without; the same lamp on the equator %.2f%% (means %.3f%% / %.3f%% / "
                "%.3f%%)\n",
                s.exponent, 100.0 * with, pole_deg, 100.0 * without, 100.0 * at_equator, 100.0 * mean_with,
                100.0 * mean_without, 100.0 * mean_equator);
    // Measured: the worst errors are on the lobe's flank, where the
    // interpolation's extra width (see the width test) moves a steep
    // profile, equally at the equator; near the zenith without the
    // correction they grow by 1.3-1.6x. So the correction stays on, and
    // with it the zenith is no worse than the equator.
    EXPECT_LE(with, 1.05 * at_equator);
    EXPECT_GT(without, 1.2 * at_equator);
  }
}

// Seams (a smooth sky with a lamp on the +X/+Z edge): jumps between
// neighbouring texels per radian, across face edges against inside faces.
struct Jumps {
  double inside = 0.0, across = 0.0;
  double worst_ratio = 0.0;  // across-edge jump / the jump of the pair just inside, per edge texel
};

Jumps jumps(const CubeMapRGB& cube) {
  Jumps j;
  const int n = cube.face_size;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const glm::dvec3 a = cubeTexelCenterDirection(face, x, y, n);
        for (auto [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{-1, 0}, std::pair{0, -1}}) {
          const int nx = x + dx, ny = y + dy;
          glm::dvec3 b;
          glm::vec3 vb;
          const bool inside = nx >= 0 && ny >= 0 && nx < n && ny < n;
          if (inside) {
            b = cubeTexelCenterDirection(face, nx, ny, n);
            vb = cube.texel(face, nx, ny);
          } else {
            // One texel further out in the face plane lands on the neighbouring face.
            const auto on_cube = [](const glm::dvec3& d) {
              return d / std::max(std::abs(d.x), std::max(std::abs(d.y), std::abs(d.z)));
            };
            const glm::dvec3 a1 = on_cube(cubeTexelCenterDirection(face, x - dx, y - dy, n));
            b = glm::normalize(2.0 * on_cube(a) - a1);
            const CubeTexelCoord c = directionToCubeCoord(b);
            const int bx = std::clamp(static_cast<int>(c.s * n), 0, n - 1), by = std::clamp(static_cast<int>(c.t * n), 0, n - 1);
            b = cubeTexelCenterDirection(c.face, bx, by, n);
            vb = cube.texel(c.face, bx, by);
          }
          const double jump = glm::length(glm::dvec3(cube.texel(face, x, y) - vb)) / testing::angleBetweenRad(a, b);
          (inside ? j.inside : j.across) = std::max(inside ? j.inside : j.across, jump);
          if (!inside) {
            const glm::dvec3 a1 = cubeTexelCenterDirection(face, x - dx, y - dy, n);
            const double inner = glm::length(glm::dvec3(cube.texel(face, x, y) - cube.texel(face, x - dx, y - dy))) /
                                 testing::angleBetweenRad(a, a1);
            j.worst_ratio = std::max(j.worst_ratio, jump / std::max(inner, 1e-3));
          }
        }
      }
  return j;
}

TEST(GlossyMaps, NoSeamsAtFaceEdges) {
  const glm::dvec3 edge_axis = glm::normalize(glm::dvec3(1.0, 0.2, 1.0));
  const CubeMapRGB input = cubeFrom(64, lamp(edge_axis, 4.0 * M_PI / 180.0, 5.0, smoothSky));
  for (int level : {0, 1}) {
    const CubeMapRGB out = glossyMap(input, defaultGlossyLevel(level));
    const Jumps j = jumps(out);
    CubeMapRGB seamed = out;
    for (glm::vec3& t : seamed.faces[4]) t *= 1.02f;
    const Jumps js = jumps(seamed);
    std::printf("[ measure  ] seams, level %d: max jump per rad across edges %.3f, inside faces %.3f, worst local "
                "ratio %.2f; with a 2%% step on +Z: %.3f / %.3f, ratio %.2f\n",
                level, j.across, j.inside, j.worst_ratio, js.across, js.inside, js.worst_ratio);
    // The brief's criterion, over the whole map (the lamp's flank dominates "inside"):
    EXPECT_LE(j.across, j.inside);
    // A local one, which a 2% step between faces breaks (measured 4.9 and
    // 10.4): each across-edge jump against the one just inside. Smooth
    // content reaches 3.6 where the gradient turns within a texel (its inner
    // jump is near 0), so 4 is an empirical margin, not a derived bound.
    EXPECT_LE(j.worst_ratio, 4.0);
    EXPECT_GT(js.worst_ratio, 4.0);
  }
}

// Glossiness 1 and 0 reproduce the mirror and diffuse terms bit for bit
// (the ladder position is exact at both ends and the other rung is not
// read); in between, R is the linear mix of the two nearest rungs.
TEST(GlossyShading, EndsAreExactAndMiddleInterpolates) {
  const auto constant = [](int size, glm::vec3 v) {
    CubeMapRGB c(size);
    for (auto& f : c.faces) f.assign(f.size(), v);
    return c;
  };
  const CubeMapRGB diffuse = constant(8, {0.1f, 0.2f, 0.3f});
  const CubeMapRGB mirror = cubeFrom(16, smoothSky);
  const CubeMapRGB glossy0 = constant(8, {0.7f, 0.5f, 0.3f});
  const CubeMapRGB glossy1 = constant(8, {0.4f, 0.4f, 0.9f});
  const std::vector<const CubeMapRGB*> glossy{&glossy0, &glossy1};
  SurfaceMaterial material;
  material.k_diffuse = 0.6f;
  material.k_reflect = 0.5f;
  const SceneLighting lighting;
  const glm::vec3 n = glm::normalize(glm::vec3(0.2f, -0.3f, 0.9f));
  const glm::vec3 v = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
  const glm::vec3 today = shadeSurface(n, v, diffuse, mirror, material, lighting);
  EXPECT_FALSE(needsGlossy(material));
  EXPECT_EQ(shadeSurface(n, v, diffuse, mirror, glossy, material, lighting), today);  // default glossiness 1
  material.glossiness = 0.0f;
  EXPECT_FALSE(needsGlossy(material));
  const glm::vec3 diffuse_term = material.k_diffuse * diffuse.sampleBilinear(glm::dvec3(n)) * material.albedo;
  EXPECT_EQ(shadeSurface(n, v, diffuse, mirror, glossy, material, lighting),
            diffuse_term + material.k_reflect * diffuse.sampleBilinear(glm::dvec3(n)));
  // Rungs at glossiness 1, 2/3, 1/3, 0; 0.5 lies halfway between glossy0 and glossy1.
  material.glossiness = 0.5f;
  EXPECT_TRUE(needsGlossy(material));
  const glm::vec3 expected = diffuse_term + material.k_reflect * glm::mix(glossy0.faces[0][0], glossy1.faces[0][0], 0.5f);
  const glm::vec3 got = shadeSurface(n, v, diffuse, mirror, glossy, material, lighting);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 1e-6f);  // a few float operations near 1
  // Without glossy maps the same material goes between mirror and diffuse.
  const ReflectionLadderBlend none = reflectionLadderBlend(0.5f, 0);
  EXPECT_EQ(none.lower, 0);
  EXPECT_FLOAT_EQ(none.toward_next, 0.5f);
}

}  // namespace
}  // namespace probelight::ibl
