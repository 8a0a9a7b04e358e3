// One view's measurement of the world-aligned probe, with how sure it is of
// each texel, for ibl::ProbeAccumulator: from the ball's reflection map,
// and from the frame around the ball for the directions the ball hides.
//
// Confidence is 1 / sigma^2 of the direction a sample really came from, in
// rad^-2: a sample read from the wrong direction is what makes a view's
// radiance wrong (the radiance's own noise is the accumulator's noise
// model). Its parts:
//  - The ball's pixel footprint. A mirror ball of image radius R px maps
//    the reflected direction at angle alpha from the eye to image radius
//    R sin(alpha / 2) (orthographically: Lambert's equal-area projection),
//    so along the radius one pixel spans 2 / (R cos(theta)) radians, theta
//    the incidence angle (alpha = 180 deg - 2 theta ... the rim, theta -> 90
//    deg, spans without bound). A pixel's footprint (1/12 px^2, a uniform
//    pixel) and the pose's error in placing the ball (pose_sigma_px) are
//    turned into radians by that.
//  - The ball's edge: within edge_mix_px of the outline a bilinear sample
//    reaches pixels beside the ball; the distance short of it adds to the
//    pixel error.
//  - The texel's own size (its angle^2 / 12), so that no sample is
//    infinitely sure.
//  - Exposure: a clipped sample is a lower bound (its flag), whatever its
//    confidence.
//  - For the frame around the ball: the parallax between the camera and the
//    ball. A pixel of the frame shows direction r as seen from the camera,
//    the ball from its centre, |b x r| apart (b = camera - ball). Toward the
//    ground (below the ball), the ground plane of the tag is where the ball
//    sees, so the pixel showing that very ground point is read: no parallax
//    on a flat matte floor. Where the ball itself hides that point from the
//    camera (the ground just behind it), and upward, the camera's own ray
//    along r is read: sigma = |b x r| / d, d the ground point's distance
//    from the ball, or upward the light's, unknown, taken as at least
//    background_min_distance_m.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_accumulator.hpp"

namespace probelight::ibl {

struct ObservationSettings {
  // The ball's image placement error from the pose, px (one sigma). Real
  // frames' outlines were within 0.01 px of the image's; a hand-held
  // camera's motion blur and rolling shutter make it larger.
  double pose_sigma_px = 0.25;
  // A bilinear sample reaches one pixel: nearer the outline, it mixes the
  // ball with what is beside it.
  double edge_mix_px = 1.0;
  // The frame around the ball.
  bool use_frame = true;
  // Lights and walls above the ground are taken as at least this far from
  // the ball (a room); nearer things have more parallax than the confidence
  // says.
  double background_min_distance_m = 2.0;
  // A pixel this near the ball's or the post's outline is not background:
  // the lens blurs the outline over a pixel or two.
  double exclusion_margin_px = 2.0;
};

// The texel-centre directions of a cube of face size n (face-major, as the
// probe's texels), made once per size and shared.
const std::vector<glm::vec3>& texelDirections(int n);

// Confidence of the ball's sample of direction r_w (unit) in `view`
// (0 where the ball does not show it).
double ballSampleConfidence(const MirrorBallView& view, const glm::dvec3& r_w, double texel_angle_rad,
                            const ObservationSettings& settings);

// The ball's samples: `map` the reflection cube this view made (GPU or CPU,
// camera linear / reflectance), `validity` its alpha (null: the texels
// reflectedDirectionToPixel finds in this view),
// `still_clipped` a bracket's per-texel flags (null: a texel is a lower
// bound where a channel reaches clip_level).
ProbeObservation observeBall(const MirrorBallView& view, const CubeMapRGB& map, const std::vector<float>* validity,
                             const std::vector<std::uint8_t>* still_clipped, double clip_level,
                             const ObservationSettings& settings);
// The same into `observation` (reset to the map's face size), whose storage
// a caller at frame rate keeps from frame to frame.
void observeBall(const MirrorBallView& view, const CubeMapRGB& map, const std::vector<float>* validity,
                 const std::vector<std::uint8_t>* still_clipped, double clip_level, const ObservationSettings& settings,
                 ProbeObservation& observation);

// A frame pixel's camera-linear RGB (the reference exposure's units), and
// whether some channel clipped.
using LinearPixelReader = std::function<glm::dvec3(int x, int y, bool& clipped)>;

// Where the ball shows nothing (its blind spot in this view), the frame's
// pixel that shows the same light, with the confidence above (source 2).
// Returns how many texels it gave. Pixels on the ball, within the margin of
// it, on the post (rig.post_radius_m), or off the frame are not read. Where
// the ball shows anything, its sample stays, however unsure: a sun
// squeezed into the rim spreads over many texels with its energy kept, and
// a sharp sample of part of them would take that energy away.
long addFrameAroundBall(ProbeObservation& observation, const MirrorBallView& view, const RigGeometry& rig,
                        const LinearPixelReader& read, const ObservationSettings& settings);

}  // namespace probelight::ibl
