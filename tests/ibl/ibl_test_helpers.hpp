// Shared set-ups for the ibl suite: kiosk-like camera poses and direction sets.
#pragma once

#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/mirror_ball.hpp"

namespace probelight::ibl::testing {

// Rotation taking unit vector `from` onto unit vector `to` (Rodrigues), the
// smallest such rotation; `from` and `to` must not be opposite.
inline glm::dmat3 rotationBetween(const glm::dvec3& from, const glm::dvec3& to) {
  const glm::dvec3 axis = glm::cross(from, to);
  const double sine = glm::length(axis);
  const double cosine = glm::dot(from, to);
  if (sine < 1e-15) return glm::dmat3(1.0);
  const glm::dvec3 k = axis / sine;
  const glm::dmat3 K(glm::dvec3(0, k.z, -k.y), glm::dvec3(-k.z, 0, k.x), glm::dvec3(k.y, -k.x, 0));  // columns
  return glm::dmat3(1.0) + sine * K + (1.0 - cosine) * K * K;
}

// Upright camera (image x horizontal, world +Z up on screen) at `camera_w`,
// turned so that world point `target_w` lies on the undistorted ray through
// `target_px`.
inline PoseCamFromWorld poseSeeingPointAtPixel(const CameraIntrinsics& camera, const glm::dvec3& camera_w,
                                               const glm::dvec3& target_w, const glm::dvec2& target_px) {
  const glm::dvec3 forward = glm::normalize(target_w - camera_w);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(0, 0, 1)));
  const glm::dvec3 down = glm::cross(forward, right);
  // Rows of R are the camera axes in W; glm matrices are built from columns.
  const glm::dmat3 looking_at_target = glm::transpose(glm::dmat3(right, down, forward));
  const glm::dvec3 ray_cam = glm::normalize(glm::dvec3((target_px.x - camera.cx_px) / camera.fx_px,
                                                       (target_px.y - camera.cy_px) / camera.fy_px, 1.0));
  PoseCamFromWorld pose;
  pose.R_cam_from_world = rotationBetween(glm::dvec3(0, 0, 1), ray_cam) * looking_at_target;
  pose.t_cam_from_world = -(pose.R_cam_from_world * camera_w);
  return pose;
}

// Roughly uniform unit directions (Fibonacci sphere), deterministic.
inline std::vector<glm::dvec3> fibonacciDirections(int count) {
  std::vector<glm::dvec3> directions;
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / count;
    const double ring = std::sqrt(1.0 - z * z);
    directions.push_back({ring * std::cos(golden_angle * i), ring * std::sin(golden_angle * i), z});
  }
  return directions;
}

inline double angleBetweenRad(const glm::dvec3& a, const glm::dvec3& b) {
  // atan2 form stays accurate for tiny angles, where acos(dot) loses digits.
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// A 640x480 camera with moderate (webcam-like) distortion.
inline CameraIntrinsics kioskCamera() {
  CameraIntrinsics camera;
  camera.distortion = {-0.12, 0.05, 0.0008, -0.0005, -0.01};
  return camera;
}

// The rig's ball (3 cm radius) seen from `distance_m`, slightly above it as
// at the kiosk, with its centre imaged at `ball_px`.
inline MirrorBallView kioskBallView(double distance_m, const glm::dvec2& ball_px) {
  MirrorBallView view;
  view.camera = kioskCamera();
  view.center_w = {0.12, 0.0, 0.08};
  view.radius_m = 0.03;
  const glm::dvec3 toward_camera = glm::normalize(glm::dvec3(-0.3, -1.0, 0.6));
  view.pose = poseSeeingPointAtPixel(view.camera, view.center_w + distance_m * toward_camera, view.center_w, ball_px);
  return view;
}

}  // namespace probelight::ibl::testing
