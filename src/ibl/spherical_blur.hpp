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
// 2. East pass, kernel cos^2, into a latitude-longitude map of
//    intermediate_rows x 2 intermediate_rows texels (eastPassToLatLong):
//    texel (theta, phi) holds the integral along the great circle through
//    it with the east tangent there.
// 3. North pass, kernel cos, on that map (northPassOnLatLong). Its taps run
//    along the texel's meridian, where the east tangent is the texel's own
//    (up to sign past the pole, and the kernels are even), so they are the
//    texels of its column (folded over the pole onto the opposite column),
//    one row apart: no interpolation at all. Then the cube of
//    output_face_size is resampled from it bilinearly (latLongToCube); E is
//    smooth (a cosine lobe's convolution), so this costs far less than
//    interpolating the sharp east-pass map would.
//    Why not cube maps in between: every north sweep crosses a pole of the
//    east tangent field (+Z or -Z, where "east" is undefined: any tangent
//    field on the sphere has such points), and near it a cube's neighbouring
//    texels were integrated along circles of very different orientations (up
//    to 90 degrees apart), so interpolating them is wrong by tens of percent
//    under a bright lamp; correcting that per tap (integrating the east
//    circle afresh near the poles) cost 61% of all taps. Neighbouring
//    columns of a latitude-longitude map differ by 2 pi / width of
//    orientation everywhere, poles included, and the map has no face edges.
//    Measured on a 6-degree lamp 500x the sky (tests/ibl): worst normal 8.2%
//    with the cube intermediate and its pole correction, 5.9% this way.
// 4. Validity (1 = seen, 0 = blind spot) is carried like a premultiplied
//    alpha and divided out at the end (normalised convolution), so the blind
//    spot is filled with the weighted mean of what the ball saw nearby
//    instead of darkening the normals that face it.
//
// A latitude-longitude map: texel (x, y) is the direction at colatitude
// theta = (y + 0.5) pi / height from +Z and azimuth phi = (x + 0.5) 2 pi / width
// from +X toward +Y, i.e. (sin theta cos phi, sin theta sin phi, cos theta).
struct LatLongRGB {
  int width = 0;
  int height = 0;
  std::vector<glm::vec3> texels;  // texels[y * width + x]

  LatLongRGB() = default;
  LatLongRGB(int width_px, int height_px);
  glm::vec3& texel(int x, int y) { return texels[static_cast<size_t>(y) * width + x]; }
  const glm::vec3& texel(int x, int y) const { return texels[static_cast<size_t>(y) * width + x]; }
  // Bilinear between texel centres, wrapping in phi. theta may run past a
  // pole (below 0 or above pi): it is folded back onto the meridian
  // phi + pi, so a sweep along a meridian crosses the pole continuously.
  // Within half a row of a pole the nearest row is used (clamped).
  glm::vec3 sampleBilinear(double theta_rad, double phi_rad) const;
};

// Colatitude from +Z and azimuth of a direction (any length > 0).
double colatitudeRad(const glm::dvec3& direction);
double azimuthRad(const glm::dvec3& direction);

// Step 2: the east cos^2 pass (half_taps as SphericalBlurPass) of `input`
// into a rows x 2 rows latitude-longitude map.
LatLongRGB eastPassToLatLong(const CubeMapRGB& input, int rows, int half_taps);
// Step 3: the north cos pass on such a map (height even): output texel
// (x, y) is the cos(j pi / height)-weighted mean of texels (x, y + j),
// |j| <= height / 2, where a row past a pole is the mirrored row of column
// x + width / 2 (width = 2 height).
LatLongRGB northPassOnLatLong(const LatLongRGB& input);
// Bilinear resampling (LatLongRGB::sampleBilinear) at each cube texel centre.
CubeMapRGB latLongToCube(const LatLongRGB& input, int face_size);

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
  // Rows of the latitude-longitude maps (even; columns: twice as many): the
  // north pass has intermediate_rows + 1 taps, pi / intermediate_rows apart.
  int intermediate_rows = 32;
  int output_face_size = 16;
  int half_taps = 16;  // 33 taps a pass, 5.5 degrees apart
};

// `validity`, when given, has one weight per texel laid out like
// CubeMapRGB::faces (face-major, row-major); radiance there is ignored where
// the weight is 0.
CubeMapRGB irradianceOverPiByCosinePasses(const CubeMapRGB& radiance, const CosineIrradianceSettings& settings,
                                          const std::vector<float>* validity = nullptr);

}  // namespace probelight::ibl
