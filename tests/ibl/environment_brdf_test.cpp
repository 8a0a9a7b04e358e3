#include "core/math_constants.hpp"
#include "ibl/environment_brdf.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace probelight::ibl {
namespace {

// The same integral by another road: over the directions l of the
// hemisphere on a (cos theta, phi) grid, with the BRDF written out,
//   f = D(h) G(v, l) F(v, h) / (4 (n.l) (n.v)),  D = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2),
// no importance sampling. Fine enough for lobes wider than the grid
// (roughness >= 0.3: alpha >= 0.09 rad against a 0.0025-rad step).
EnvironmentBrdf bruteForceOverLightDirections(double roughness, double n_dot_v) {
  const double alpha = roughness * roughness, k = alpha / 2.0;
  const double vx = std::sqrt(1.0 - n_dot_v * n_dot_v), vz = n_dot_v;
  constexpr int kTheta = 600, kPhi = 1200;
  EnvironmentBrdf sum;
  for (int a = 0; a < kTheta; ++a) {
    // cos theta uniform: dl = d(cos theta) d phi.
    const double lz = (a + 0.5) / kTheta, ls = std::sqrt(1.0 - lz * lz);
    for (int b = 0; b < kPhi; ++b) {
      const double phi = 2.0 * kPi * (b + 0.5) / kPhi;
      const double lx = ls * std::cos(phi), ly = ls * std::sin(phi);
      double hx = vx + lx, hy = ly, hz = vz + lz;
      const double length = std::sqrt(hx * hx + hy * hy + hz * hz);
      hx /= length, hy /= length, hz /= length;
      const double v_dot_h = vx * hx + vz * hz;
      const double d_denominator = hz * hz * (alpha * alpha - 1.0) + 1.0;
      const double d = alpha * alpha / (kPi * d_denominator * d_denominator);
      const double g = (n_dot_v / (n_dot_v * (1.0 - k) + k)) * (lz / (lz * (1.0 - k) + k));
      const double base = d * g / (4.0 * lz * n_dot_v) * lz;  // f without F, times n.l
      const double fresnel = std::pow(1.0 - v_dot_h, 5.0);
      sum.scale += base * (1.0 - fresnel);
      sum.bias += base * fresnel;
    }
  }
  const double cell = (1.0 / kTheta) * (2.0 * kPi / kPhi);
  return {sum.scale * cell, sum.bias * cell};
}

TEST(EnvironmentBrdf, ImportanceSamplingAgreesWithAPlainIntegralOverLightDirections) {
  for (const double roughness : {0.3, 0.5, 0.8, 1.0})
    for (const double n_dot_v : {0.1, 0.4, 0.7, 1.0}) {
      const EnvironmentBrdf sampled = integrateEnvironmentBrdf(roughness, n_dot_v, 4096);
      const EnvironmentBrdf plain = bruteForceOverLightDirections(roughness, n_dot_v);
      // Both are quadratures of one smooth integrand: they agree to the
      // coarser one's error, well under one 8-bit code (0.0039).
      EXPECT_NEAR(sampled.scale, plain.scale, 2e-3) << roughness << " " << n_dot_v;
      EXPECT_NEAR(sampled.bias, plain.bias, 2e-3) << roughness << " " << n_dot_v;
    }
}

// A mirror (alpha -> 0) reflects l = reflect(-v, n) only, with h = n, G = 1
// and Fresnel at v.h = n.v: scale = 1 - (1 - n.v)^5, bias = (1 - n.v)^5.
TEST(EnvironmentBrdf, ASmoothSurfaceIsSchlicksFresnelAtTheViewAngle) {
  for (const double n_dot_v : {0.05, 0.2, 0.5, 1.0}) {
    const EnvironmentBrdf mirror = integrateEnvironmentBrdf(0.0, n_dot_v);
    const double fresnel = std::pow(1.0 - n_dot_v, 5.0);
    // roughness 1e-3: alpha 1e-6, a lobe of 1e-6 rad; G's k = 5e-7.
    EXPECT_NEAR(mirror.scale, 1.0 - fresnel, 1e-4) << n_dot_v;
    EXPECT_NEAR(mirror.bias, fresnel, 1e-4) << n_dot_v;
  }
}

// Single-scattering microfacets lose energy, never make it: with F0 = 1
// (F = 1) the reflectance scale + bias is at most 1, and both are >= 0.
TEST(EnvironmentBrdf, NoSurfaceReflectsMoreThanItReceives) {
  for (int i = 0; i <= 10; ++i)
    for (int j = 1; j <= 10; ++j) {
      const EnvironmentBrdf value = integrateEnvironmentBrdf(i / 10.0, j / 10.0);
      EXPECT_GE(value.scale, 0.0);
      EXPECT_GE(value.bias, 0.0);
      EXPECT_LE(value.scale + value.bias, 1.0 + 1e-6) << i << " " << j;
    }
}

// Why the table and not Karis' analytic fit: the fit's error, measured.
TEST(EnvironmentBrdf, KarisMobileFitIsTooDarkForSmoothMetalsFacingTheViewer) {
  const EnvironmentBrdf integral = integrateEnvironmentBrdf(0.3, 1.0);
  const EnvironmentBrdf fit = karisMobileEnvironmentBrdf(0.3, 1.0);
  EXPECT_GT(integral.scale + integral.bias, 0.98);
  EXPECT_LT(fit.scale + fit.bias, 0.85) << "a metal (F0 = 1) 15% too dark";
  double worst_metal = 0.0;
  for (int i = 0; i <= 20; ++i)
    for (int j = 1; j <= 20; ++j) {
      const EnvironmentBrdf a = integrateEnvironmentBrdf(i / 20.0, j / 20.0), b = karisMobileEnvironmentBrdf(i / 20.0, j / 20.0);
      worst_metal = std::max(worst_metal, std::abs(a.scale + a.bias - b.scale - b.bias));
    }
  std::printf("Karis 2014 fit: worst metal (F0 = 1) error %.3f\n", worst_metal);
}

// The table read as the GPU reads it, against the integral between its
// texels: 8-bit texels are within half a code (0.002); the bilinear filter
// adds the function's bend over a texel, largest at grazing views (where
// Fresnel turns fastest) and between the table's quadrature points. The
// bound is three codes of the 8-bit composite (0.0118; measured 0.011 at
// roughness 0.49, n.v 0.15), and the mean within one code (measured 0.57:
// the two channels' rounding alone is about 0.35).
TEST(EnvironmentBrdf, TheTableIsWithinThreeCodesOfTheIntegralEverywhere) {
  const EnvironmentBrdfTable table;
  EXPECT_EQ(table.luminanceAlpha().size(), static_cast<std::size_t>(2 * table.size() * table.size()));
  double worst_dielectric = 0.0, worst_metal = 0.0, sum_metal = 0.0;
  int count = 0;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) {
      const double roughness = i / 40.0, n_dot_v = std::max(0.01, (j / 40.0) * (j / 40.0));
      const EnvironmentBrdf truth = integrateEnvironmentBrdf(roughness, n_dot_v, 4096);
      const EnvironmentBrdf read = table.lookup(roughness, n_dot_v);
      worst_dielectric = std::max(worst_dielectric, std::abs(0.04 * (read.scale - truth.scale) + read.bias - truth.bias));
      const double metal = std::abs(read.scale + read.bias - truth.scale - truth.bias);
      worst_metal = std::max(worst_metal, metal);
      sum_metal += metal;
      ++count;
    }
  std::printf("table %dx%d: worst dielectric (F0 = 0.04) %.4f, worst metal %.4f, mean metal %.4f\n", table.size(),
              table.size(), worst_dielectric, worst_metal, sum_metal / count);
  EXPECT_LT(worst_dielectric, 3.0 / 255.0);
  EXPECT_LT(worst_metal, 3.0 / 255.0);
  EXPECT_LT(sum_metal / count, 1.0 / 255.0);
}

TEST(EnvironmentBrdf, TableCoordinatesPutTheEndsOnTexelCentres) {
  const EnvironmentBrdfTable table(32, 64);
  EXPECT_FLOAT_EQ(table.coordinate(0.0f), 0.5f / 32.0f);
  EXPECT_FLOAT_EQ(table.coordinate(1.0f), 31.5f / 32.0f);
  EXPECT_FLOAT_EQ(table.coordinate(2.0f), 31.5f / 32.0f) << "clamped";
}

}  // namespace
}  // namespace probelight::ibl
