// The tag's printed white border as a diffuse reference: the film
// industry's chrome ball plus grey ball, done with the marker the kiosk
// already tracks. It needs no bracket and works in every frame.
//
// The border is Lambertian with a known albedo (rig.yaml tag_white_albedo),
// so its camera-linear value L says the irradiance on the ground there:
// E_border = pi * L / albedo. The ball's 8-bit map integrates to less than
// that whenever a lamp, window or sun clipped in it: the clipped texels hold
// 1 (times 1/reflectance) where the truth is far brighter. The shortfall
// E_border - E_ball is given back to the clipped texels of the upper
// hemisphere (those the ground sees), as one added radiance over them, so
// each gets energy in proportion to its solid angle (weighted by the cosine
// the ground sees it at, so that the ground's irradiance then matches
// E_border exactly).
//
// What it cannot know: how the missing light divides between several
// clipped regions (each gets its share by area), and clipped light below
// the horizon (the ground does not see it). The ball and its post also
// shade the border a little (not modelled: for a 3 cm ball 10 cm away,
// under 3% of the sky); partly shadowed borders are caught patch by patch.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"

namespace probelight::ibl {

// The printed white ring of an AprilTag, in the tag's frame W (tag centred
// on the origin in z = 0, edges along X and Y): the square annulus between
// the half-sizes inner and outer. libapriltag prints a one-cell white ring
// just outside the detected quad, or, for reversed-border families
// (tagStandard41h12), just inside it; a cell is tag_size / width_at_border.
struct WhiteRing {
  double inner_half_m = 0.0;
  double outer_half_m = 0.0;
};
WhiteRing tagWhiteRing(int width_at_border_cells, bool reversed_border, double tag_size_m);

struct WhiteBorderSettings {
  CameraTransfer camera_transfer;
  // As ibl::HdrMergeSettings: codes at or above clip_code are clipped,
  // at or below dark_code mostly noise.
  int clip_code = 250;
  int dark_code = 6;
  // Patches along each side of the ring; each is averaged on its own so a
  // shadow across part of the border is seen as patches darker than the rest.
  int patches_per_side = 4;
  // Narrower than this in the image (the ring's middle half, which is what
  // is sampled), pose error and blur mix in the black border or the floor.
  double min_sampled_width_px = 1.0;
  // A patch darker than this fraction of the border's lit level lies in a
  // shadow. On a flat print a few centimetres across, the light differs
  // only by shadows; 0.8 leaves room for a print's sheen at grazing views.
  double shadow_fraction = 0.8;
};

// "42%": a fraction as a whole percentage, for messages.
std::string percentText(double fraction);

enum class WhiteBorderStatus { kMeasured, kNotInView, kTooSmall, kClipped, kTooDark };
const char* toString(WhiteBorderStatus status);

struct WhiteBorderReading {
  WhiteBorderStatus status = WhiteBorderStatus::kNotInView;
  std::string message;
  glm::dvec3 linear_rgb{0.0};  // mean camera-linear value of the lit patches
  int patches = 0;             // inside the frame
  int patches_lit = 0;         // used for linear_rgb
  int patches_clipped = 0;
  int patches_dark = 0;
  int patches_shadowed = 0;
  double sampled_width_px = 0.0;  // the ring's middle half, narrowest side in the image
};

// Encoded RGB (0..255) of pixel (x, y); only called inside the frame.
using RgbPixelReader = std::function<glm::u8vec3(int x, int y)>;

// Samples the middle half of the ring's width (pose error and blur stay
// clear of the black cells and the floor) and the middle of each side
// (corners left out), about one sample a pixel.
WhiteBorderReading readWhiteBorder(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const WhiteRing& ring,
                                   const RgbPixelReader& read_pixel, const WhiteBorderSettings& settings);

// Texels of a face_size cube whose directions hold a ball pixel that
// clipped in the frame (some channel >= clip_code), as flags at
// face * n^2 + y * n + x. A sun smaller than a texel clips a pixel or two
// that the map's texel-centre sampling can step over; this cannot.
std::vector<std::uint8_t> clippedTexelMask(const MirrorBallView& view, const RgbPixelReader& read_pixel, int clip_code,
                                           int face_size);

enum class WhiteReferenceStatus {
  kCorrected,      // the shortfall was given to the clipped texels
  kNothingClipped, // no clipped texel above the horizon: the map stands (a consistency check is reported)
  kNoShortfall,    // clipped, but the border says the ball misses almost nothing
  kBorderDarker,   // the border is darker than the ball's own estimate: in shadow, or albedo too high
  kBorderUnusable, // the reading was not kMeasured
};
const char* toString(WhiteReferenceStatus status);

struct WhiteReferenceResult {
  WhiteReferenceStatus status = WhiteReferenceStatus::kBorderUnusable;
  std::string message;
  glm::dvec3 border_irradiance_rgb{0.0};  // pi * L / albedo
  glm::dvec3 map_irradiance_rgb{0.0};     // the map's upward irradiance before
  glm::dvec3 added_radiance_rgb{0.0};     // on each clipped upper texel
  double clipped_upper_sr = 0.0;          // solid angle of the clipped texels above the horizon
  double clipped_lower_sr = 0.0;          // ... below it (not corrected: the ground does not see them)
};

// A border darker than the ball's estimate by more than this fraction is
// not trusted (kBorderDarker). Below it the two agree within what the
// albedo's print tolerance (~5%), the ball's blind spot and the rig's shade
// on the border explain.
constexpr double kBorderDarkerTolerance = 0.10;

// Corrects `map` (the ball's 8-bit map: texels whose largest channel is at
// or above clip_level, or flagged in clipped_mask, are clipped) in place.
// Texels with validity 0 are neither counted nor changed. Upward
// irradiance: the upper hemisphere only, as the ground sees it.
WhiteReferenceResult correctClippedWithWhiteBorder(CubeMapRGB& map, const std::vector<float>* validity,
                                                   const WhiteBorderReading& border, double tag_white_albedo,
                                                   double clip_level,
                                                   const std::vector<std::uint8_t>* clipped_mask = nullptr);

// The light a clipped region really held, as a few directional lights for
// the frame-rate shading: the texels that clipped (largest channel >=
// clip_level in either map, or flagged in clipped_mask) take the energy
// `true_map` has there beyond `clipped_map`'s, grouped greedily (brightest first) into clusters of angular
// radius cluster_radius_rad. Each light is its cluster's first moment
// sum(dL * solid angle * omega): its irradiance is exact for every normal
// that sees the whole cluster. At most max_lights; the rest join the
// nearest. irradiance_rgb is E at a normal facing the light.
struct ClippedLight {
  glm::dvec3 direction_w{0.0, 0.0, 1.0};
  glm::dvec3 irradiance_rgb{0.0};
  // The texels it came from (face * n^2 + y * n + x of the map it was
  // found in) and the share of its energy each held: which directions must
  // still clip for it to still be there (stillClippedShare).
  std::vector<std::uint32_t> texels;
  std::vector<float> texel_share;
};

// The share of `light`'s energy whose texels still clip (largest channel
// at clip_level, to within a half float's rounding: maps clamped at the
// clip level hold it as a float, a half float or an 8-bit code, each
// rounded its own way) in `live`, a later 8-bit map of the same size: 1 while the
// sun or lamp is still there, 0 once it has gone (a cloud, a switch). The
// frame-rate maps stay 8-bit; this is how they keep carrying the clipped
// energy the last calibration measured, and drop it when it leaves.
double stillClippedShare(const ClippedLight& light, const CubeMapRGB& live, double clip_level);
// The same, and the share of `light`'s energy in texels that no longer clip
// and that `resolved` (per texel of `live`; null: none) flags.
struct ClippedShares {
  double still_clipped = 0.0;
  double resolved = 0.0;
};
ClippedShares clippedShares(const ClippedLight& light, const CubeMapRGB& live, double clip_level,
                            const std::vector<std::uint8_t>* resolved);
std::vector<ClippedLight> clippedLights(const CubeMapRGB& true_map, const CubeMapRGB& clipped_map,
                                        const std::vector<float>* validity, double clip_level,
                                        const std::vector<std::uint8_t>* clipped_mask = nullptr, int max_lights = 4,
                                        double cluster_radius_rad = 0.44);

}  // namespace probelight::ibl
