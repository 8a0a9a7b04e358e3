// The 9-coefficient spherical-harmonics (SH9) irradiance of Ramamoorthi &
// Hanrahan (2001, "An efficient representation for irradiance environment
// maps"): the alternative to the blurred diffuse map. Radiance is projected
// onto the real SH basis of bands 0-2; irradiance is then a quadratic
// polynomial in the normal. Exact for radiance in bands 0-2 (a constant, a
// linear gradient, a quadratic); for other radiance the error is what the
// cosine lobe lets through above band 2 (R&H: ~1% on average for typical
// environments, more for a near-delta light: see tests/ibl/spherical_harmonics_test.cpp).
//
// Basis order and normalisation (unit direction (x, y, z), world frame W):
//   0: Y00  = 0.282095                    1: Y1-1 = 0.488603 y
//   2: Y10  = 0.488603 z                  3: Y11  = 0.488603 x
//   4: Y2-2 = 1.092548 xy                 5: Y2-1 = 1.092548 yz
//   6: Y20  = 0.315392 (3z^2 - 1)         7: Y21  = 1.092548 xz
//   8: Y22  = 0.546274 (x^2 - y^2)
// (the constants are sqrt(1/4pi), sqrt(3/4pi), sqrt(15/4pi), sqrt(5/16pi),
// sqrt(15/16pi); the code uses them unrounded).
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

constexpr int kSH9Count = 9;

struct SH9RGB {
  std::array<glm::dvec3, kSH9Count> coefficients{};  // L_lm per colour channel, order as above
};

// The nine basis functions at unit direction `d`.
std::array<double, kSH9Count> sh9Basis(const glm::dvec3& d);

// Projection of a radiance cube map onto the basis, weighted by each texel's
// solid angle (cubeTexelSolidAngle) at its centre direction.
//
// It is computed as the least-squares fit in that weighted inner product,
// c = G^-1 b with b_k = sum_i w_i dOmega_i Y_k(omega_i) L_i and the Gram
// matrix G_kj = sum_i w_i dOmega_i Y_k Y_j (w_i = 1 without validity). With
// every texel valid, G is the identity up to the cube's quadrature error
// (~1e-4), so this is the usual projection; solving with G instead of
// assuming I makes radiance in bands 0-2 come back exactly on any grid.
//
// `validity` (laid out like CubeMapRGB::faces, as EnvironmentMaps::read*
// returns alpha): texels of weight 0 (the ball's blind spot, where rgb is 0
// as "unknown", not "dark") are left out of both b and G, and fractional
// weights scale a texel's share. Solving with the Gram matrix of the seen
// texels is the renormalisation: the coefficients are the SH9 function that
// best fits the directions that were seen, so the blind spot is filled by
// that fit instead of darkening the side facing it. The usual fix, scaling
// the plain projection by 4pi / (seen solid angle), is exact for the
// constant band only; this is exact for all of bands 0-2. When the seen
// region is too small for a stable fit of all nine (a Cholesky pivot of G,
// which is 1 for the whole sphere, below 1e-3: extrapolating into the unseen
// directions would amplify noise ~30x), it fits bands 0-1 only, and failing
// that band 0 alone (the weighted mean of what was seen), leaving the higher
// coefficients 0. Nothing seen at all gives zero coefficients.
SH9RGB projectToSH9(const CubeMapRGB& radiance, const std::vector<float>* validity = nullptr);

// The quadratic-form constants of R&H's equation 13 as the paper prints them
// (6 digits); c1 = A2 * sqrt(15/16pi), c2 = A1 * sqrt(3/4pi) / 2,
// c3 = 3 A2 * sqrt(5/16pi), c4 = A0 * sqrt(1/4pi), c5 = A2 * sqrt(5/16pi),
// with the cosine lobe's band weights A0 = pi, A1 = 2pi/3, A2 = pi/4.
constexpr double kSH9C1 = 0.429043;
constexpr double kSH9C2 = 0.511664;
constexpr double kSH9C3 = 0.743125;
constexpr double kSH9C4 = 0.886227;
constexpr double kSH9C5 = 0.247708;

// Irradiance E(n) (not divided by pi) from R&H's equation 13, the polynomial
// form:
//   E(n) = c1 L22 (x^2 - y^2) + c3 L20 z^2 + c4 L00 - c5 L20
//        + 2 c1 (L2-2 xy + L21 xz + L2-1 yz) + 2 c2 (L11 x + L1-1 y + L10 z),
// (x, y, z) = normalize(normal). Unclamped: a band-limited fit of a bright
// small light rings, and can go slightly negative facing away from it.
glm::dvec3 irradianceFromSH9(const SH9RGB& sh, const glm::dvec3& normal);

// The same polynomial folded for a shader, divided by pi (the diffuse map's
// convention, E = pi * D): E(n) / pi = p0 + p1 x + p2 y + p3 z + p4 xy + p5 yz
// + p6 xz + p7 z^2 + p8 (x^2 - y^2). Every monomial lies in [-1, 1], so in a
// 10-bit-mantissa (mediump) shader the rounding error of each term is
// relative to its coefficient, never amplified.
std::array<glm::dvec3, kSH9Count> sh9DiffusePolynomial(const SH9RGB& sh);

// Diffuse cube map storing max(0, E(n)) / pi at each texel centre: what
// EnvironmentMaps::updateDiffuseFromSH9 renders, and what ObjectCompositor
// reads with the normal (E = pi * D). Negative ringing is clamped to 0 (light
// is never negative, and the 8-bit storage cannot hold it either).
CubeMapRGB sh9DiffuseMap(const SH9RGB& sh, int face_size);

}  // namespace probelight::ibl
