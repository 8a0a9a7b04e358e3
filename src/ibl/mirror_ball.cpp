#include "ibl/mirror_ball.hpp"

#include <cmath>

#include "core/finite_vector.hpp"
#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

std::optional<glm::dvec2> reflectedDirectionToPixel(const MirrorBallView& view, const glm::dvec3& reflected_w,
                                                    int iterations) {
  const glm::dvec3 camera_center_w = view.pose.cameraCenterWorld();
  // NaN fails every test below (a length < threshold, a dot <= 0), so a NaN
  // direction or pose would come out as a NaN pixel: no pixel instead.
  if (!allFinite(reflected_w) || glm::length(reflected_w) == 0.0 || !allFinite(camera_center_w) ||
      !allFinite(view.center_w) || !std::isfinite(view.radius_m))
    return std::nullopt;
  const glm::dvec3 r = glm::normalize(reflected_w);
  // In ball units (centre 0, radius 1) the surface point is the normal
  // itself and the camera sits at `eye`. The seed treats the camera as
  // infinitely far along `eye`.
  const glm::dvec3 eye = (camera_center_w - view.center_w) / view.radius_m;
  glm::dvec3 bisector = glm::normalize(eye) + r;
  if (glm::length(bisector) < kBlindSpotLength) return std::nullopt;
  glm::dvec3 normal = glm::normalize(bisector);
  for (int i = 0; i < iterations; ++i) {
    // The fixed-point step re-aims the view vector from the current surface
    // point: target = normalize(normalize(eye - n) + r), written with one
    // square root, as (eye - n) + |eye - n| r points the same way.
    const glm::dvec3 to_eye = eye - normal;
    const double to_eye_squared = glm::dot(to_eye, to_eye);
    const double to_eye_length = std::sqrt(to_eye_squared);
    bisector = to_eye + to_eye_length * r;
    if (glm::length(bisector) < kBlindSpotLength * to_eye_length) return std::nullopt;
    const glm::dvec3 target = glm::normalize(bisector);
    // Newton's step on the same equation. n, r and the eye lie in one plane;
    // with theta the normal's angle from the eye's direction, the step maps
    // theta to (alpha - beta(theta)) / 2, beta the view vector's angle, whose
    // derivative is beta' = (eye.n - 1) / |eye - n|^2. Newton divides the
    // step by 1 + beta'/2: quadratic convergence where the plain step gains
    // only a factor of radius / (2 distance).
    const double relaxation = 2.0 * to_eye_squared / (2.0 * to_eye_squared + glm::dot(eye, normal) - 1.0);
    normal += relaxation * (target - normal);
    // The step runs along a chord, shorter than 1 by about step^2 / 8
    // (~1e-4); one Newton step of 1/sqrt from 1 restores the unit length to
    // the square of that, with no square root (the shader's costliest op).
    normal *= 1.5 - 0.5 * glm::dot(normal, normal);
  }
  const glm::dvec3 surface_w = view.center_w + view.radius_m * normal;
  const glm::dvec3 to_camera = camera_center_w - surface_w;
  // On a convex ball a point is visible exactly when its normal faces the eye.
  if (glm::dot(normal, to_camera) <= 0.0) return std::nullopt;
  const glm::dvec3 surface_cam = view.pose.toCamera(surface_w);
  if (!(surface_cam.z > 0.0)) return std::nullopt;
  const glm::dvec2 pixel = projectToPixel(view.camera, surface_cam);
  // Non-finite intrinsics (or an overflow) still give no pixel, not a NaN one.
  if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y)) return std::nullopt;
  return pixel;
}

std::optional<glm::dvec3> pixelToReflectedDirection(const MirrorBallView& view, const glm::dvec2& pixel) {
  const glm::dvec3 ray_w =
      glm::normalize(glm::transpose(view.pose.R_cam_from_world) * pixelToCameraRay(view.camera, pixel));
  const glm::dvec3 origin_w = view.pose.cameraCenterWorld();
  // |origin + t ray - centre|^2 = radius^2 with |ray| = 1.
  const glm::dvec3 centre_to_origin = origin_w - view.center_w;
  const double half_b = glm::dot(ray_w, centre_to_origin);
  const double c = glm::dot(centre_to_origin, centre_to_origin) - view.radius_m * view.radius_m;
  const double discriminant = half_b * half_b - c;
  // Written so that NaN (from a NaN pixel, pose or calibration) fails them too.
  if (!(discriminant >= 0.0)) return std::nullopt;
  const double t_nearest = -half_b - std::sqrt(discriminant);
  if (!(t_nearest > 0.0)) return std::nullopt;  // ball behind the camera, or camera inside it
  const glm::dvec3 normal = (origin_w + t_nearest * ray_w - view.center_w) / view.radius_m;
  const glm::dvec3 reflected = glm::normalize(ray_w - 2.0 * glm::dot(ray_w, normal) * normal);
  if (!allFinite(reflected)) return std::nullopt;
  return reflected;
}

glm::dvec2 orthographicSphereMapPixel(const MirrorBallView& view, const glm::dvec3& reflected_w) {
  const glm::dmat3& R = view.pose.R_cam_from_world;
  // Row 2 of R is the camera z axis in W; v points from the ball back to the camera.
  const glm::dvec3 toward_camera_w = -glm::dvec3(R[0][2], R[1][2], R[2][2]);
  const glm::dvec3 normal_cam = R * glm::normalize(glm::normalize(reflected_w) + toward_camera_w);
  const glm::dvec3 center_cam = view.pose.toCamera(view.center_w);
  const glm::dvec2 center_px = projectToPixel(view.camera, center_cam);
  const double radius_over_depth = view.radius_m / center_cam.z;
  return center_px + glm::dvec2(view.camera.fx_px * radius_over_depth * normal_cam.x,
                                view.camera.fy_px * radius_over_depth * normal_cam.y);
}

}  // namespace probelight::ibl
