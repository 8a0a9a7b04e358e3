// CPU reference of stage 3: a separable Gaussian blur on the sphere of
// directions. Each pass samples along great circles, so there are no seams at
// cube face edges; two passes along orthogonal tangents give the 2-D blur.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "ibl/cube_map.hpp"

namespace probelight::ibl {

enum class BlurAxis {
  kEast = 0,   // tangent t = normalize(cross(world +Z, n)); at the poles (|cross| < 1e-4) t = +X
  kNorth = 1,  // tangent t = cross(n, east tangent)
};

// The 1-D kernel of a pass.
//  kGaussian: exp(-a^2 / (2 sigma^2)), taps at i * 3 sigma / half_taps.
//  kCosineSquared, kCosine: cos^2(a) and cos(a) over [-pi/2, pi/2], taps at
//    the centres of 2 * half_taps + 1 equal cells (a_i = i * pi / (2 half_taps + 1)).
// An east pass with kCosineSquared followed by a north pass with kCosine is
// exactly the cosine-weighted irradiance divided by pi, up to quadrature:
// with e the east tangent at n and N = n x e, every direction of the
// hemisphere around n is w(a, b) = cos a (cos b n + sin b N) + sin a e for one
// (a, b) in [-pi/2, pi/2]^2 (latitude a about the pole e, longitude b), its
// solid angle is cos a da db, and n.w = cos a cos b. So
//   E(n) = int L(w) max(0, n.w) dw = int cos b [int cos^2 a L(w(a, b)) da] db,
// and the east samples of the north pass's points all share the tangent e
// (they lie in the plane through n and +Z). The discrete weights are
// normalised, which divides by int cos^2 = pi/2 and int cos = 2: the result
// is E(n) / pi, the convention of the diffuse map.
enum class BlurKernel { kGaussian, kCosineSquared, kCosine };

struct SphericalBlurPass {
  BlurAxis axis = BlurAxis::kEast;
  double sigma_rad = 0.6;  // kGaussian only
  int half_taps = 8;       // samples at i * step for i in [-half_taps, half_taps]
  BlurKernel kernel = BlurKernel::kGaussian;
};

// Angle and (unnormalised) weight of tap i in [-half_taps, half_taps].
double blurTapAngleRad(const SphericalBlurPass& pass, int i);
double blurTapWeight(const SphericalBlurPass& pass, double angle_rad);

glm::dvec3 blurTangent(const glm::dvec3& n, BlurAxis axis);

// Output texel (x, y) of face f, with centre direction n, is
//   sum_i w_i * input.sampleBilinear(cos(a_i) n + sin(a_i) t) / sum_i w_i,
//   a_i = i * step, w_i = exp(-a_i^2 / (2 sigma^2)).
CubeMapRGB sphericalBlurPass(const CubeMapRGB& input, int output_face_size, const SphericalBlurPass& pass);

// Area-weighted average of factor x factor texel blocks (each texel weighted
// by its solid angle), so a small bright light keeps its energy when the map
// shrinks to the spacing of the blur's taps.
CubeMapRGB downsampleCubeMap(const CubeMapRGB& input, int factor);

// The diffuse map as E(n) / pi by the two cosine passes.
//
// 1. The radiance map is shrunk to prefilter_face_size (downsampleCubeMap),
//    about the tap spacing, so that a small lamp cannot fall between taps.
// 2. East pass, kernel cos^2, into intermediate_face_size.
// 3. North pass, kernel cos, into output_face_size. Every north sweep crosses
//    a pole of the east tangent field (+Z or -Z, where "east" is undefined:
//    any tangent field on the sphere has such points), and near it the
//    intermediate texels were integrated along east circles of every
//    orientation, so interpolating them is wrong by up to tens of percent
//    under a bright lamp. North taps within pole_direct_deg of +-Z therefore
//    integrate their east circle directly from the prefiltered map, with the
//    output texel's own tangent. Measured on a 6-degree lamp 500x the sky
//    (tests/ibl): worst normal 36-60% without this, 8% with it.
// 4. Validity (1 = seen, 0 = blind spot) is carried like a premultiplied
//    alpha and divided out at the end (normalised convolution), so the blind
//    spot is filled with the weighted mean of what the ball saw nearby
//    instead of darkening the normals that face it.
// A cube map with validity carried beside it and the radiance premultiplied
// by it, so every pass is the same weighted sum for both and the final
// division (normalised convolution) fills what the ball did not see.
struct ValidityWeightedCube {
  CubeMapRGB premultiplied;
  CubeMapRGB validity;  // same value in r, g, b
  // (premultiplied rgb, validity), both sampled bilinearly.
  glm::dvec4 sample(const glm::dvec3& direction) const;
};

// Premultiplies `radiance` by `validity` (all 1 when null; laid out like
// CubeMapRGB::faces) and shrinks both to prefilter_face_size with
// downsampleCubeMap.
ValidityWeightedCube prefilterWithValidity(const CubeMapRGB& radiance, const std::vector<float>* validity,
                                           int prefilter_face_size);

struct CosineIrradianceSettings {
  int prefilter_face_size = 16;
  int intermediate_face_size = 32;
  int output_face_size = 16;
  int half_taps = 16;  // 33 taps a pass, 5.5 degrees apart
  double pole_direct_deg = 20.0;
};

// `validity`, when given, has one weight per texel laid out like
// CubeMapRGB::faces (face-major, row-major); radiance there is ignored where
// the weight is 0.
CubeMapRGB irradianceOverPiByCosinePasses(const CubeMapRGB& radiance, const CosineIrradianceSettings& settings,
                                          const std::vector<float>* validity = nullptr);

}  // namespace probelight::ibl
