// The split-sum environment BRDF of a glTF metallic-roughness surface (Karis,
// "Real Shading in Unreal Engine 4", 2013): with GGX microfacets of
// alpha = roughness^2, Smith's shadowing in Schlick's form with k = alpha / 2
// (the image-based-lighting choice of that paper) and Schlick's Fresnel
// F = F0 + (1 - F0) (1 - v.h)^5, the specular reflectance towards v,
//   integral over l of f(v, l) (n.l) dl = F0 * scale + bias,
// with scale and bias functions of roughness and n.v only. The specular
// light is then the prefiltered map's radiance times F0 * scale + bias.
//
// How a shader gets scale and bias (the renderer's choice, measured in
// tests/ibl/environment_brdf_test.cpp):
// - Karis' analytic approximation for mobile (2014) needs no texture, but is
//   0.16 off at roughness 0.3 facing the viewer (scale 0.83 where the
//   integral gives 0.99), a 16% darker metal: more than the accuracy a
//   model's metals are held to.
// - EnvironmentBrdfTable: the integral itself on a grid of 8-bit texels
//   (GL_LUMINANCE_ALPHA, core GLES2: no float texture needed), read with the
//   GPU's bilinear filter: within 3 codes of the integral everywhere, 0.6 of
//   a code on average, at 48 x 48 (32 x 32 was 5.7 codes off at grazing views
//   of near-mirrors).
#pragma once

#include <cstdint>
#include <vector>

namespace probelight::ibl {

struct EnvironmentBrdf {
  double scale = 0.0;  // times F0
  double bias = 0.0;
};

// The reference: the integral by importance sampling of the GGX normal
// distribution over `samples` Hammersley points (deterministic). roughness
// in [0, 1] (0 is taken as 1e-3: a perfect mirror is a delta), n_dot_v in
// (0, 1] (below 1e-4 taken as 1e-4: the integrand divides by it).
EnvironmentBrdf integrateEnvironmentBrdf(double roughness, double n_dot_v, int samples = 1024);

// Karis' "Physically Based Shading on Mobile" (2014) fit, for comparison.
EnvironmentBrdf karisMobileEnvironmentBrdf(double roughness, double n_dot_v);

// The integral on size x size texels: column i at roughness i / (size - 1),
// row j at sqrt(n.v) = j / (size - 1) (the square root spends the rows
// where the function bends, at grazing views). Texel (i, j) is bytes
// 2 (j size + i) (scale) and + 1 (bias), each round(255 value).
class EnvironmentBrdfTable {
 public:
  // 48 x 48 texels of 512 samples: 1.2 M samples (about 60 ms on this
  // project's x86 machine), made once, when a material needs it.
  explicit EnvironmentBrdfTable(int size = 48, int samples = 512);

  int size() const { return size_; }
  const std::vector<std::uint8_t>& luminanceAlpha() const { return texels_; }

  // The texture coordinate of a value on the grid's axis (roughness, or
  // sqrt(n.v)), for a texture sampled with GL_LINEAR and CLAMP_TO_EDGE:
  // (x (size - 1) + 0.5) / size, so 0 and 1 fall on texel centres.
  float coordinate(float x) const;
  // What the GPU's bilinear filter returns for (roughness, n_dot_v), from
  // the 8-bit texels, in doubles: the table's own error against the
  // integral is measured with it.
  EnvironmentBrdf lookup(double roughness, double n_dot_v) const;

 private:
  int size_;
  std::vector<std::uint8_t> texels_;
};

}  // namespace probelight::ibl
