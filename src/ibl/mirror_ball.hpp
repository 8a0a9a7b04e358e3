// Exact perspective geometry of a mirror ball seen by a calibrated camera:
// which image pixel shows the reflection of a given world direction, and the
// reverse. Uses each pixel's true camera ray, not the orthographic sphere-map
// approximation (seed A's fixed view vector).
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::ibl {

// |e + r| below this means the reflected direction points straight away from
// the camera (the blind spot), where the ball normal is undefined.
constexpr double kBlindSpotLength = 1e-6;

struct MirrorBallView {
  CameraIntrinsics camera;
  PoseCamFromWorld pose;
  glm::dvec3 center_w{0.0};
  double radius_m = 0.0;
};

// The pixel whose camera ray, reflected off the ball, travels along world
// direction `reflected_w` (any length > 0). Empty when no such point is
// visible (the blind spot directly behind the ball). `iterations` Newton
// steps on the ball normal n = normalize(to_camera + reflected): each
// squares the error (in units of the distance / radius ratio), so 1 step
// leaves under 0.01 px at a ball 20 cm away and 3 steps reach well below
// 1e-6 rad at kiosk distances. Exactly, with O the camera centre, C the ball
// centre, E = (O - C) / radius and r = normalize(reflected_w):
//   n = normalize(normalize(E) + r)
//   repeat `iterations` times:
//     u = E - n; t = normalize(u + |u| r)          (the fixed-point target)
//     n += (t - n) * 2|u|^2 / (2|u|^2 + E.n - 1)   (Newton's step length)
//     n *= 1.5 - n.n / 2                           (back to unit length)
//   P = C + radius n (from the final n); pixel = projectToPixel(P in camera)
// Empty when any |u + |u| r| < kBlindSpotLength |u|, when the final P faces away from
// the camera (dot(n, normalize(O - P)) <= 0) or when P is not in front of it,
// and empty (never a NaN pixel) for a zero or non-finite direction, view or
// resulting pixel.
std::optional<glm::dvec2> reflectedDirectionToPixel(const MirrorBallView& view, const glm::dvec3& reflected_w,
                                                    int iterations = 8);
// World direction (unit) in which the camera ray through `pixel` leaves the
// ball after reflection off its nearest hit. Empty when the ray misses the
// ball, and for non-finite input. `pixel` is in OpenCV pixel coordinates, as
// projectToPixel returns.
std::optional<glm::dvec3> pixelToReflectedDirection(const MirrorBallView& view, const glm::dvec2& pixel);
// Seed A's approximation, kept only to measure how wrong it is: ball normal
// n = normalize(r + v) with v = the negated camera z axis in W (fixed along
// the optical axis, pointing back toward the camera); the pixel is the
// projected (distorted) ball centre + (fx, fy) * radius / depth * (n_cam.x, n_cam.y),
// depth being the ball centre's camera z.
glm::dvec2 orthographicSphereMapPixel(const MirrorBallView& view, const glm::dvec3& reflected_w);

}  // namespace probelight::ibl
