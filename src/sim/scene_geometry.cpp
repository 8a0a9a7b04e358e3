#include "sim/scene_geometry.hpp"

#include <cmath>
#include <numbers>

#include <opencv2/calib3d.hpp>

namespace probelight::sim {

std::array<glm::dvec3, 4> tagCornersWorld(double tag_size_m) {
  const double h = tag_size_m / 2.0;
  return {glm::dvec3{-h, -h, 0.0}, glm::dvec3{h, -h, 0.0}, glm::dvec3{h, h, 0.0}, glm::dvec3{-h, h, 0.0}};
}

std::vector<glm::dvec2> projectWorldPoints(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                           const std::vector<glm::dvec3>& points_w) {
  if (points_w.empty()) return {};
  std::vector<cv::Point3d> object;
  object.reserve(points_w.size());
  for (const glm::dvec3& p : points_w) object.emplace_back(p.x, p.y, p.z);
  cv::Matx33d rotation;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rotation(r, c) = pose.R_cam_from_world[c][r];  // glm is column-major
  cv::Vec3d rvec;
  cv::Rodrigues(rotation, rvec);
  cv::Vec3d tvec(pose.t_cam_from_world.x, pose.t_cam_from_world.y, pose.t_cam_from_world.z);
  cv::Matx33d k(camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
  std::vector<double> distortion(camera.distortion.begin(), camera.distortion.end());
  std::vector<cv::Point2d> image;
  cv::projectPoints(object, rvec, tvec, k, distortion, image);
  std::vector<glm::dvec2> result;
  result.reserve(image.size());
  for (const cv::Point2d& p : image) result.emplace_back(p.x, p.y);
  return result;
}

bool pointInImage(const CameraIntrinsics& camera, const glm::dvec2& p, double margin_px) {
  // Pixel centres are integers (OpenCV); the image spans [-0.5, size - 0.5].
  return p.x >= -0.5 + margin_px && p.y >= -0.5 + margin_px && p.x <= camera.width_px - 0.5 - margin_px &&
         p.y <= camera.height_px - 0.5 - margin_px;
}

ProbeOutline probeOutline(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const glm::dvec3& center_w,
                          double radius_m, int samples) {
  ProbeOutline outline;
  const glm::dvec3 eye = pose.cameraCenterWorld();
  const glm::dvec3 to_center = center_w - eye;
  const double distance = glm::length(to_center);
  if (distance <= radius_m * 1.0001) return outline;
  const glm::dvec3 axis = to_center / distance;
  // Tangent points: a circle of radius r sqrt(d^2 - r^2) / d, centred r^2/d
  // from the sphere centre toward the eye.
  const double circle_radius = radius_m * std::sqrt(distance * distance - radius_m * radius_m) / distance;
  const glm::dvec3 circle_center = center_w - axis * (radius_m * radius_m / distance);
  glm::dvec3 helper = std::abs(axis.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
  glm::dvec3 u = glm::normalize(glm::cross(axis, helper));
  glm::dvec3 v = glm::cross(axis, u);
  std::vector<glm::dvec3> points_w;
  points_w.reserve(samples);
  for (int i = 0; i < samples; ++i) {
    double a = 2.0 * std::numbers::pi * i / samples;
    glm::dvec3 p = circle_center + circle_radius * (std::cos(a) * u + std::sin(a) * v);
    if (pose.toCamera(p).z <= 1e-6) return outline;  // part of the outline behind the camera
    points_w.push_back(p);
  }
  outline.polygon_px = projectWorldPoints(camera, pose, points_w);
  double twice_area = 0.0;
  glm::dvec2 centroid_sum{0.0};
  bool all_inside = true;
  for (int i = 0; i < samples; ++i) {
    const glm::dvec2& a = outline.polygon_px[i];
    const glm::dvec2& b = outline.polygon_px[(i + 1) % samples];
    double cross = a.x * b.y - b.x * a.y;
    twice_area += cross;
    centroid_sum += (a + b) * cross;
    all_inside = all_inside && pointInImage(camera, a, 0.0);
  }
  if (std::abs(twice_area) < 1e-12) return outline;
  outline.center_px = centroid_sum / (3.0 * twice_area);
  outline.radius_px = std::sqrt(std::abs(twice_area) / 2.0 / std::numbers::pi);
  outline.valid = true;
  outline.fully_visible = all_inside;
  return outline;
}

bool tagFullyVisible(const CameraIntrinsics& camera, const RigGeometry& rig, double post_radius_m,
                     const PoseCamFromWorld& pose, double margin_px) {
  auto corners = tagCornersWorld(rig.tag_size_m);
  std::vector<glm::dvec3> corner_points(corners.begin(), corners.end());
  for (const glm::dvec3& p : corner_points)
    if (pose.toCamera(p).z <= 1e-6) return false;
  for (const glm::dvec2& p : projectWorldPoints(camera, pose, corner_points))
    if (!pointInImage(camera, p, margin_px)) return false;
  const glm::dvec3 eye = pose.cameraCenterWorld();
  const glm::dvec2 post_xy{rig.probe_center_w.x, rig.probe_center_w.y};
  const double post_top_z = rig.probe_center_w.z - rig.probe_radius_m;
  constexpr int kGrid = 9;
  for (int iy = 0; iy < kGrid; ++iy) {
    for (int ix = 0; ix < kGrid; ++ix) {
      glm::dvec3 p{(ix / double(kGrid - 1) - 0.5) * rig.tag_size_m, (iy / double(kGrid - 1) - 0.5) * rig.tag_size_m,
                   0.0};
      glm::dvec3 to_point = p - eye;
      double distance = glm::length(to_point);
      glm::dvec3 dir = to_point / distance;
      auto hit_ball = intersectSphere(eye, dir, rig.probe_center_w, rig.probe_radius_m);
      if (hit_ball && *hit_ball < distance) return false;
      auto hit_post = intersectPost(eye, dir, post_xy, post_radius_m, post_top_z);
      if (hit_post && *hit_post < distance) return false;
    }
  }
  return true;
}

}  // namespace probelight::sim
