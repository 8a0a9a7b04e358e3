// CPU reference of the glossy maps: the reflection map convolved with a
// Phong lobe cos^n(angle to the reflection direction), normalised to the
// lobe's mean radiance (a constant map stays constant; units as the mirror
// map's), in two separable passes along great circles, like the diffuse
// map's cosine passes (spherical_blur.hpp), so there are no face seams.
//
// Why the passes are exact (up to quadrature), not just "about a Gaussian":
// with e the east tangent at r and N = r x e, write a direction as
//   w(a, b) = cos a (cos b r + sin b N) + sin a e,
// (latitude a about the pole e, longitude b). Then r.w = cos a cos b and the
// solid angle is cos a da db, so
//   int L(w) cos^n(r.w) dw = int cos^n b [ int cos^(n+1) a L(w(a, b)) da ] db:
// an east pass with kernel cos^(n+1) followed by a north pass with kernel
// cos^n (the diffuse map is the case n = 1: cos^2 then cos). Both kernels are
// nearly Gaussian: ln cos a = -a^2/2 - a^4/12 - ..., so
// cos^n a = exp(-a^2 / (2 / n)) * exp(-n a^4 / 12 - ...): sigma = 1 / sqrt(n),
// and at the 3-sigma cut the quartic term is 6.75 / n (5% of a 1% weight for
// n = 128; 42% for n = 16, so the exact kernel, not the Gaussian, is used).
// Taps cover [-3 sigma, 3 sigma]: the weight there is exp(-4.5) ~ 1%, and
// a Gaussian loses 0.27% of its mass beyond 3 sigma per axis (cos^n's tail
// is lighter still). Weights are normalised per pass, which divides by the
// lobe's integral: the result is the lobe's mean radiance.
//
// The kernel is evaluated as exp(-m s(a)) with s(a) the series of -ln cos a
// to a^10 (glossyTapWeight): the GPU uses the same formula, because pow(cos
// a, 129) in a mediump shader would turn cos's 2^-11 rounding into 6%
// errors, while the series' terms are all positive and well conditioned.
// Its truncation is < 5e-5 * m relative at a = 0.75 rad (the widest tap of
// n = 16), measured in tests/ibl/glossy_maps_test.cpp.
//
// Why these levels (defaults): the ladder mirror (n = inf) -> 128 -> 16 ->
// diffuse (a clamped-cosine lobe about the normal, roughly n ~ 1) steps the
// lobe's width geometrically, sigma 0 -> 0.088 -> 0.25 -> ~0.6 rad (x2.8 a
// step), so that interpolating between the two nearest maps (seed C) never
// mixes lobes of very different widths. n = 128 is seed C's glossy2.
// Face sizes follow sigma: 32^2 (texel ~0.0625 rad at the face centre,
// 0.7 sigma) for n = 128, 16^2 (0.125 rad, 0.5 sigma) for n = 16. The
// prefilter (downsampleCubeMap) shrinks the 64^2 reflection map to the
// output size first, so that the 17 taps of a pass (spacing 0.033 and 0.094
// rad) never step over a texel.
//
// The pole of the east tangent field: as in the diffuse map, north taps
// within pole_direct_deg of +-Z integrate their east circle directly from
// the prefiltered map with the output texel's own tangent. For narrow lobes
// the affected region is small (only texels within ~3 sigma + pole_direct_deg
// of a pole have such taps); tests/ibl/glossy_maps_test.cpp measures the
// error with and without it for a lamp near the zenith.
//
// Validity is carried as in the diffuse map (premultiplied, divided out at
// the end: normalised convolution); `coverage`, when given, receives the
// blurred validity.
#pragma once

#include <vector>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

struct GlossyLevelSettings {
  double exponent = 128.0;       // n of cos^n
  int prefilter_face_size = 32;  // the reflection map is downsampled to this first
  int intermediate_face_size = 64;
  int output_face_size = 32;
  int half_taps = 8;             // 2 half_taps + 1 taps a pass over [-3 sigma, 3 sigma]
  double pole_direct_deg = 10.0;
};

// The defaults of the two levels (n = 128 at 32^2, n = 16 at 16^2).
GlossyLevelSettings defaultGlossyLevel(int level);

// sigma = 1 / sqrt(n); tap i in [-half_taps, half_taps] is at i * 3 sigma / half_taps.
double glossyTapAngleRad(double exponent, int half_taps, int i);
// exp(-m * s(a)), s(a) = a^2/2 + a^4/12 + a^6/45 + 17 a^8/2520 + 31 a^10/14175 (~ -ln cos a):
// m = n + 1 for the east pass (the solid angle's cos a), n for the north pass.
double glossyTapWeight(double power, double angle_rad);

CubeMapRGB glossyMap(const CubeMapRGB& radiance, const GlossyLevelSettings& settings,
                     const std::vector<float>* validity = nullptr, std::vector<float>* coverage = nullptr);

}  // namespace probelight::ibl
