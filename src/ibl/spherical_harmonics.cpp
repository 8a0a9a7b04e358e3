#include "ibl/spherical_harmonics.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>

namespace probelight::ibl {

namespace {

const double kY0 = 0.5 * std::sqrt(1.0 / M_PI);         // sqrt(1/4pi)
const double kY1 = std::sqrt(3.0 / (4.0 * M_PI));        // sqrt(3/4pi)
const double kY2 = std::sqrt(15.0 / (4.0 * M_PI));       // sqrt(15/4pi)
const double kY20 = std::sqrt(5.0 / (16.0 * M_PI));      // sqrt(5/16pi)
const double kY22 = std::sqrt(15.0 / (16.0 * M_PI));     // sqrt(15/16pi)

// Smallest Cholesky pivot (of a Gram matrix that is I for the whole sphere)
// accepted for the least-squares fit; below it the fit's extrapolation into
// the unseen directions amplifies noise by more than 1 / sqrt(pivot) ~ 30x.
constexpr double kMinPivot = 1e-3;

using Matrix9 = std::array<std::array<double, kSH9Count>, kSH9Count>;

// In-place Cholesky factorisation G = L L^T (lower triangle of `g` becomes
// L). pivots[j] is the j-th pivot (L_jj^2); it stops at the first pivot <= 0
// and returns how many it completed. The leading m x m block of L is the
// factor of G's leading m x m block, so one factorisation serves the fits of
// bands 0-2 (m = 9), 0-1 (m = 4) and 0 (m = 1).
int choleskyFactor(Matrix9& g, std::array<double, kSH9Count>& pivots) {
  for (int j = 0; j < kSH9Count; ++j) {
    double diagonal = g[j][j];
    for (int k = 0; k < j; ++k) diagonal -= g[j][k] * g[j][k];
    pivots[j] = diagonal;
    if (!(diagonal > 0.0)) return j;
    const double root = std::sqrt(diagonal);
    g[j][j] = root;
    for (int i = j + 1; i < kSH9Count; ++i) {
      double value = g[i][j];
      for (int k = 0; k < j; ++k) value -= g[i][k] * g[j][k];
      g[i][j] = value / root;
    }
  }
  return kSH9Count;
}

// Solves the leading m x m system L L^T x = b for the three channels at
// once; x[m..8] stay 0.
std::array<glm::dvec3, kSH9Count> choleskySolve(const Matrix9& l, const std::array<glm::dvec3, kSH9Count>& b,
                                                int m) {
  std::array<glm::dvec3, kSH9Count> y{};
  for (int i = 0; i < m; ++i) {
    glm::dvec3 value = b[i];
    for (int k = 0; k < i; ++k) value -= l[i][k] * y[k];
    y[i] = value / l[i][i];
  }
  std::array<glm::dvec3, kSH9Count> x{};
  for (int i = m - 1; i >= 0; --i) {
    glm::dvec3 value = y[i];
    for (int k = i + 1; k < m; ++k) value -= l[k][i] * x[k];
    x[i] = value / l[i][i];
  }
  return x;
}

}  // namespace

std::array<double, kSH9Count> sh9Basis(const glm::dvec3& d) {
  return {kY0,
          kY1 * d.y,
          kY1 * d.z,
          kY1 * d.x,
          kY2 * d.x * d.y,
          kY2 * d.y * d.z,
          kY20 * (3.0 * d.z * d.z - 1.0),
          kY2 * d.x * d.z,
          kY22 * (d.x * d.x - d.y * d.y)};
}

namespace {

// What projectToSH9 needs per texel, independent of the map: Y_k(omega_i) *
// dOmega_i, and the whole sphere's Gram matrix. Built once per face size
// (the kiosk uses one), so a projection is 27 multiply-adds per texel plus
// 45 per texel left out.
struct ProjectionTable {
  int face_size = 0;
  std::vector<std::array<double, kSH9Count>> basis;           // Y_k(omega_i), face-major
  std::vector<std::array<double, kSH9Count>> weighted_basis;  // Y_k(omega_i) dOmega_i
  std::vector<double> solid_angles;                           // dOmega_i
  Matrix9 gram{};                                             // over every texel
};

std::shared_ptr<const ProjectionTable> projectionTable(int face_size) {
  static std::mutex mutex;
  static std::shared_ptr<const ProjectionTable> cached;
  std::lock_guard<std::mutex> lock(mutex);
  if (cached && cached->face_size == face_size) return cached;
  auto table = std::make_shared<ProjectionTable>();
  table->face_size = face_size;
  const size_t count = static_cast<size_t>(kCubeFaceCount) * face_size * face_size;
  table->basis.resize(count);
  table->weighted_basis.resize(count);
  table->solid_angles.resize(count);
  size_t i = 0;
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x, ++i) {
        const double d_omega = cubeTexelSolidAngle(x, y, face_size);
        table->basis[i] = sh9Basis(cubeTexelCenterDirection(face, x, y, face_size));
        table->solid_angles[i] = d_omega;
        for (int k = 0; k < kSH9Count; ++k) {
          table->weighted_basis[i][k] = table->basis[i][k] * d_omega;
          for (int j = 0; j <= k; ++j) table->gram[k][j] += table->weighted_basis[i][k] * table->basis[i][j];
        }
      }
    }
  }
  cached = std::move(table);
  return cached;
}

}  // namespace

SH9RGB projectToSH9(const CubeMapRGB& radiance, const std::vector<float>* validity) {
  SH9RGB sh;
  const int n = radiance.face_size;
  if (n <= 0) return sh;
  // A validity of another layout cannot be matched to the texels (and would
  // be read out of bounds): nothing is known, so zero coefficients.
  if (validity != nullptr && validity->size() != static_cast<size_t>(kCubeFaceCount) * n * n) return sh;
  const std::shared_ptr<const ProjectionTable> table = projectionTable(n);
  const size_t texels_per_face = static_cast<size_t>(n) * static_cast<size_t>(n);
  std::array<glm::dvec3, kSH9Count> b{};
  // The Gram matrix of the seen texels: the whole sphere's minus what each
  // texel's missing weight (1 - w) takes away; the blind spot is a few
  // percent of the sphere, so this touches few texels.
  Matrix9 gram = table->gram;
  double seen_solid_angle = 4.0 * M_PI;
  for (int face = 0; face < kCubeFaceCount; ++face) {
    const auto& texels = radiance.faces[static_cast<size_t>(face)];
    for (size_t index = 0; index < texels_per_face; ++index) {
      const size_t i = static_cast<size_t>(face) * texels_per_face + index;
      double weight = 1.0;
      if (validity != nullptr) {
        const double v = (*validity)[i];
        weight = v > 0.0 ? std::min(v, 1.0) : 0.0;  // NaN counts as unseen
      }
      // A non-finite texel (NaN, Inf) is unknown like the blind spot: left
      // out, so one bad texel cannot turn all nine coefficients into NaN.
      const glm::vec3& texel = texels[index];
      if (!std::isfinite(texel.r) || !std::isfinite(texel.g) || !std::isfinite(texel.b)) weight = 0.0;
      if (weight < 1.0) {
        const double missing = 1.0 - weight;
        seen_solid_angle -= missing * table->solid_angles[i];
        for (int k = 0; k < kSH9Count; ++k) {
          for (int j = 0; j <= k; ++j) gram[k][j] -= missing * table->weighted_basis[i][k] * table->basis[i][j];
        }
        if (weight == 0.0) continue;
      }
      const glm::dvec3 value = glm::dvec3(texels[index]) * weight;
      for (int k = 0; k < kSH9Count; ++k) b[k] += table->weighted_basis[i][k] * value;
    }
  }
  // Subtracting the unseen texels leaves round-off (~1e-16 * 4pi) where all
  // were unseen: treat a seen solid angle below one part in 1e9 as none.
  if (!(seen_solid_angle > 1e-9 * 4.0 * M_PI)) return sh;
  for (int k = 0; k < kSH9Count; ++k) {
    for (int j = k + 1; j < kSH9Count; ++j) gram[k][j] = gram[j][k];
  }
  Matrix9 factor = gram;
  std::array<double, kSH9Count> pivots{};
  const int completed = choleskyFactor(factor, pivots);
  // The largest band count whose fit is stable: 9, else 4, else 1 (the
  // constant band alone, i.e. the solid-angle-weighted mean of what was seen).
  int bands = 1;
  for (int m : {kSH9Count, 4}) {
    if (completed >= m && *std::min_element(pivots.begin(), pivots.begin() + m) >= kMinPivot) {
      bands = m;
      break;
    }
  }
  if (bands == 1) {
    sh.coefficients[0] = b[0] / gram[0][0];
  } else {
    sh.coefficients = choleskySolve(factor, b, bands);
  }
  return sh;
}

glm::dvec3 irradianceFromSH9(const SH9RGB& sh, const glm::dvec3& normal) {
  // A NaN or zero normal has no irradiance to speak of: 0, not NaN.
  if (!std::isfinite(normal.x) || !std::isfinite(normal.y) || !std::isfinite(normal.z) ||
      (normal.x == 0.0 && normal.y == 0.0 && normal.z == 0.0))
    return glm::dvec3(0.0);
  const glm::dvec3 n = glm::normalize(normal);
  const auto& L = sh.coefficients;
  const double x = n.x;
  const double y = n.y;
  const double z = n.z;
  // R&H equation 13, L indexed as in the header (L[6] = L20, L[8] = L22...).
  return kSH9C1 * L[8] * (x * x - y * y) + kSH9C3 * L[6] * z * z + kSH9C4 * L[0] - kSH9C5 * L[6] +
         2.0 * kSH9C1 * (L[4] * x * y + L[7] * x * z + L[5] * y * z) +
         2.0 * kSH9C2 * (L[3] * x + L[1] * y + L[2] * z);
}

std::array<glm::dvec3, kSH9Count> sh9DiffusePolynomial(const SH9RGB& sh) {
  const auto& L = sh.coefficients;
  const double inv_pi = 1.0 / M_PI;
  return {(kSH9C4 * L[0] - kSH9C5 * L[6]) * inv_pi,
          2.0 * kSH9C2 * L[3] * inv_pi,
          2.0 * kSH9C2 * L[1] * inv_pi,
          2.0 * kSH9C2 * L[2] * inv_pi,
          2.0 * kSH9C1 * L[4] * inv_pi,
          2.0 * kSH9C1 * L[5] * inv_pi,
          2.0 * kSH9C1 * L[7] * inv_pi,
          kSH9C3 * L[6] * inv_pi,
          kSH9C1 * L[8] * inv_pi};
}

CubeMapRGB sh9DiffuseMap(const SH9RGB& sh, int face_size) {
  CubeMapRGB cube(face_size);
  for (int face = 0; face < kCubeFaceCount; ++face) {
    for (int y = 0; y < face_size; ++y) {
      for (int x = 0; x < face_size; ++x) {
        const glm::dvec3 e = irradianceFromSH9(sh, cubeTexelCenterDirection(face, x, y, face_size));
        cube.texel(face, x, y) = glm::vec3(glm::max(e, glm::dvec3(0.0)) / M_PI);
      }
    }
  }
  return cube;
}

}  // namespace probelight::ibl
