#include "ibl/environment_brdf.hpp"
#include "core/math_constants.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::ibl {
namespace {

// Van der Corput's radical inverse in base 2: the Hammersley set's second
// coordinate.
double radicalInverse(std::uint32_t bits) {
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return bits * 2.3283064365386963e-10;
}

std::uint8_t toByte(double value) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0, 1.0) * 255.0));
}

}  // namespace

EnvironmentBrdf integrateEnvironmentBrdf(double roughness, double n_dot_v, int samples) {
  const double r = std::clamp(roughness, 1e-3, 1.0);
  const double nv = std::clamp(n_dot_v, 1e-4, 1.0);
  const double alpha = r * r, k = alpha / 2.0;
  // v in the x-z plane, n = +z.
  const double vx = std::sqrt(1.0 - nv * nv), vz = nv;
  const double g1_v = nv / (nv * (1.0 - k) + k);
  double scale = 0.0, bias = 0.0;
  for (int i = 0; i < samples; ++i) {
    // h from GGX's D(h) (n.h): cos^2 theta = (1 - u) / (1 + (alpha^2 - 1) u).
    const double u1 = (i + 0.5) / samples, u2 = radicalInverse(static_cast<std::uint32_t>(i));
    const double phi = 2.0 * kPi * u1;
    const double cos_theta = std::sqrt((1.0 - u2) / (1.0 + (alpha * alpha - 1.0) * u2));
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    const double hx = sin_theta * std::cos(phi), hz = cos_theta;
    const double v_dot_h = vx * hx + vz * hz;
    const double l_z = 2.0 * v_dot_h * hz - vz;  // l = reflect(-v, h), its n.l
    if (l_z <= 0.0 || v_dot_h <= 0.0) continue;
    // With h drawn from D (n.h), f (n.l) / pdf(l) = G (v.h) / ((n.h) (n.v)) times F.
    const double g = g1_v * l_z / (l_z * (1.0 - k) + k);
    const double weight = g * v_dot_h / (hz * nv);
    const double fresnel = std::pow(1.0 - v_dot_h, 5.0);
    scale += (1.0 - fresnel) * weight;
    bias += fresnel * weight;
  }
  return {scale / samples, bias / samples};
}

EnvironmentBrdf karisMobileEnvironmentBrdf(double roughness, double n_dot_v) {
  const double c0[4] = {-1.0, -0.0275, -0.572, 0.022};
  const double c1[4] = {1.0, 0.0425, 1.04, -0.04};
  double r[4];
  for (int i = 0; i < 4; ++i) r[i] = roughness * c0[i] + c1[i];
  const double a004 = std::min(r[0] * r[0], std::exp2(-9.28 * n_dot_v)) * r[0] + r[1];
  return {-1.04 * a004 + r[2], 1.04 * a004 + r[3]};
}

EnvironmentBrdfTable::EnvironmentBrdfTable(int size, int samples) : size_(std::max(size, 2)) {
  texels_.resize(static_cast<std::size_t>(2 * size_ * size_));
  for (int j = 0; j < size_; ++j) {
    const double root_n_dot_v = static_cast<double>(j) / (size_ - 1);
    for (int i = 0; i < size_; ++i) {
      const EnvironmentBrdf value =
          integrateEnvironmentBrdf(static_cast<double>(i) / (size_ - 1), root_n_dot_v * root_n_dot_v, samples);
      const std::size_t at = 2 * (static_cast<std::size_t>(j) * size_ + i);
      texels_[at] = toByte(value.scale);
      texels_[at + 1] = toByte(value.bias);
    }
  }
}

float EnvironmentBrdfTable::coordinate(float x) const {
  return (std::clamp(x, 0.0f, 1.0f) * static_cast<float>(size_ - 1) + 0.5f) / static_cast<float>(size_);
}

EnvironmentBrdf EnvironmentBrdfTable::lookup(double roughness, double n_dot_v) const {
  // GL_LINEAR on texel centres (i + 0.5) / size: position x (size - 1).
  const double x = std::clamp(roughness, 0.0, 1.0) * (size_ - 1);
  const double y = std::sqrt(std::clamp(n_dot_v, 0.0, 1.0)) * (size_ - 1);
  const int i0 = std::min(static_cast<int>(x), size_ - 2), j0 = std::min(static_cast<int>(y), size_ - 2);
  const double fx = x - i0, fy = y - j0;
  auto texel = [&](int i, int j, int channel) {
    return texels_[2 * (static_cast<std::size_t>(j) * size_ + i) + channel] / 255.0;
  };
  EnvironmentBrdf out;
  for (int channel = 0; channel < 2; ++channel) {
    const double value = (1 - fy) * ((1 - fx) * texel(i0, j0, channel) + fx * texel(i0 + 1, j0, channel)) +
                         fy * ((1 - fx) * texel(i0, j0 + 1, channel) + fx * texel(i0 + 1, j0 + 1, channel));
    (channel == 0 ? out.scale : out.bias) = value;
  }
  return out;
}

}  // namespace probelight::ibl
