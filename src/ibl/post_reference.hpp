// The ball's post as a second diffuse reference, beside the tag's white
// border (ibl/white_reference.hpp).
//
// The border measures one irradiance: the ground's, facing up. With one
// clipped source that places all the light the ball's 8-bit map misses;
// with several of unequal brightness (a stage's lamp and its bright bounce
// boards) one number cannot say how the missing light divides between them,
// and the border's rule, in proportion to solid angle, over-lights the large
// dim regions (docs/accuracy.md: the real Stage world, 87% off). A post of
// known albedo, painted matte, measures the irradiance at the horizontal
// normals of the side it turns to the camera: the normals a virtual object
// beside it shows the camera too. With those readings and the border's, the
// missing light is divided between the clipped regions by least squares:
// each region keeps its shape (the border's added radiance over its texels)
// and takes its own scale.
//
// The post stands vertically under the ball (its axis through the ball
// centre's x, y), from the ground up to the ball (rig.yaml post_radius,
// post_albedo). A pixel is read only where the post is wholly seen: its
// centre and four corners on the post, the ball not in front, and at least
// min_distance_below_ball_radii ball radii below the ball. (The ball hides
// the sky straight above from the top of the post, and a real chrome ball
// throws its reflections down onto it; one radius down, the ball covers a
// cap of 30 degrees about the zenith, which sends a horizontal normal under
// 3% of what it sees of an even sky.)
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/white_reference.hpp"

namespace probelight::ibl {

struct PostReadingSettings {
  CameraTransfer camera_transfer;
  // As WhiteBorderSettings: codes at or above clip_code are clipped, at or
  // below dark_code mostly noise.
  int clip_code = 250;
  int dark_code = 6;
  double min_distance_below_ball_radii = 1.0;
  // Readings are averaged in bins of the normal's azimuth this wide (the
  // irradiance of a cosine lobe changes by under 1% within +-7.5 degrees of
  // its peak), each from at least min_pixels_per_bin pixels.
  double bin_width_deg = 15.0;
  int min_pixels_per_bin = 3;
};

enum class PostStatus { kMeasured, kNoPost, kNotInView, kClipped, kTooDark };
const char* toString(PostStatus status);

// The irradiance a Lambertian surface with this normal receives, measured.
struct DiffuseReference {
  glm::dvec3 normal_w{0.0, 0.0, 1.0};
  glm::dvec3 irradiance_rgb{0.0};  // camera linear units, as the ball's maps
  int pixels = 0;                  // averaged over
  // A mean over the pixels of a curved surface: each one's normal (empty:
  // all have normal_w). The fit averages its model over them as the reading
  // did, which matters where the light's cosine has its kink (a sun at 90
  // degrees to the normal) inside a bin.
  std::vector<glm::dvec3> pixel_normals_w;
};

struct PostReading {
  PostStatus status = PostStatus::kNoPost;
  std::string message;
  std::vector<DiffuseReference> references;  // one an azimuth bin: pi * mean(L) / post_albedo
  int pixels_seen = 0;     // wholly on the post, in the part that is read
  int pixels_clipped = 0;  // ... with a channel clipped
  int pixels_dark = 0;     // ... with a channel in the noise
};

// Reads the post of `rig` in a frame: kNoPost where rig.post_radius_m or
// rig.post_albedo is 0, or the post is too short to have a part far enough
// below the ball; kNotInView where no pixel shows it wholly (out of frame,
// hidden, or narrower than a pixel or two); kClipped / kTooDark where every
// bin held a pixel that clipped / was lost in the noise (a bin that does is
// left out: its mean would only bound the light).
PostReading readPost(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const RigGeometry& rig,
                     const RgbPixelReader& read_pixel, const PostReadingSettings& settings);

enum class DiffuseFitStatus {
  kRefined,        // the regions' scales were fitted
  kNothingToFit,   // no clipped region, or no reference
  kInconsistent,   // a reference reads darker than the 8-bit map alone: nothing changed
};
const char* toString(DiffuseFitStatus status);

struct DiffuseFit {
  DiffuseFitStatus status = DiffuseFitStatus::kNothingToFit;
  std::string message;
  std::vector<glm::dvec3> region_direction_w;  // each region's first-moment direction
  std::vector<glm::dvec3> region_scale_rgb;    // what its added radiance was multiplied by
  // Root mean square of (model - reference) / reference over the references
  // (luminance), with the border's equal share and after the fit.
  double rms_relative_before = 0.0;
  double rms_relative_after = 0.0;
};

// A reference darker than the 8-bit map alone says by more than this
// fraction is not trusted (as kBorderDarkerTolerance for the border: an
// albedo set too high, a post in shade or not matte).
constexpr double kReferenceDarkerTolerance = 0.10;

// `corrected` is `original` (the ball's 8-bit map) with light added to its
// clipped texels (correctClippedWithWhiteBorder). The added light is
// grouped into regions as clippedLights groups it (max_regions); each
// region's added radiance is scaled, per channel, so that the map's
// irradiance at the references' normals matches them in least squares of
// the relative differences, scales >= 0. A region no reference sees keeps
// scale 1 (the border's share): a weak pull toward 1 (weight
// kRegionScalePrior against the squared relative differences) decides only
// what the readings leave open. Texels with validity 0 neither count nor
// change.
constexpr double kRegionScalePrior = 1e-4;
DiffuseFit fitClippedRegionsToReferences(CubeMapRGB& corrected, const CubeMapRGB& original,
                                         const std::vector<float>* validity, double clip_level,
                                         const std::vector<std::uint8_t>* clipped_mask,
                                         const std::vector<DiffuseReference>& references, int max_regions = 4);

// The border's reading as a reference: the ground's normal, pi * L / albedo.
DiffuseReference borderReference(const WhiteBorderReading& border, double tag_white_albedo);

// After correctClippedWithWhiteBorder gave `corrected` the border's light:
// reads the post in the frame and, where it measured, divides that light
// between the clipped regions by the border's reading and the post's
// (fitClippedRegionsToReferences). `fit` is kNothingToFit when the post was
// not read; `corrected` changes only when it is kRefined.
struct PostCorrection {
  PostReading reading;
  DiffuseFit fit;
};
PostCorrection correctClippedWithPost(CubeMapRGB& corrected, const CubeMapRGB& original,
                                      const std::vector<float>* validity, double clip_level,
                                      const std::vector<std::uint8_t>* clipped_mask, const WhiteBorderReading& border,
                                      const RigGeometry& rig, const CameraIntrinsics& camera,
                                      const PoseCamFromWorld& pose, const RgbPixelReader& read_pixel,
                                      const PostReadingSettings& settings);

}  // namespace probelight::ibl
