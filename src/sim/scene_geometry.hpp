// Geometry of the truth: where the tag's corners and the ball's outline land
// in the image (through OpenCV's camera model, distortion included), and
// whether they are in view and unoccluded.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::sim {

// The tag's outer black-border corners in W, in libapriltag's detection order
// (apriltag_detection_t::p): bottom-left, bottom-right, top-right, top-left of
// the printed image, i.e. (-s/2,-s/2), (+s/2,-s/2), (+s/2,+s/2), (-s/2,+s/2).
std::array<glm::dvec3, 4> tagCornersWorld(double tag_size_m);

// cv::projectPoints with the camera's distortion. Points must be in front of
// the camera (z_cam > 0) for the result to mean anything.
std::vector<glm::dvec2> projectWorldPoints(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                           const std::vector<glm::dvec3>& points_w);

struct ProbeOutline {
  glm::dvec2 center_px{0.0};  // area centroid of the outline polygon
  double radius_px = 0.0;     // sqrt(area / pi)
  bool valid = false;         // false when the camera is inside or behind the sphere
  bool fully_visible = false; // every outline point inside the image
  std::vector<glm::dvec2> polygon_px;
};

// Samples the sphere's silhouette (the circle where the tangent cone from the
// camera centre touches it), projects it, and measures the polygon.
ProbeOutline probeOutline(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const glm::dvec3& center_w,
                          double radius_m, int samples = 720);

// A sphere tested against many rays from one origin (a frame traces about
// half a million from its eye): what does not depend on the ray is computed
// once. Inline, so the frame's loop inlines the per-ray test.
class SphereFromOrigin {
 public:
  SphereFromOrigin(const glm::dvec3& origin, const glm::dvec3& center, double radius)
      : origin_to_center_(origin - center),
        offset_squared_minus_radius_squared_(glm::dot(origin_to_center_, origin_to_center_) - radius * radius) {}

  // t along origin + t * dir (dir unit length); nullopt on a miss. A hit
  // closer than 1e-9 is the surface the ray starts on.
  std::optional<double> intersect(const glm::dvec3& dir) const {
    const double b = glm::dot(origin_to_center_, dir);
    const double discriminant = b * b - offset_squared_minus_radius_squared_;
    if (discriminant < 0.0) return std::nullopt;
    const double root = std::sqrt(discriminant);
    double t = -b - root;
    if (t <= 1e-9) t = -b + root;
    if (t <= 1e-9) return std::nullopt;
    return t;
  }

 private:
  glm::dvec3 origin_to_center_;  // origin - center
  double offset_squared_minus_radius_squared_;
};

// A vertical cylinder of radius_m around (axis_xy, z) for z in [0, top_z],
// tested against many rays from one origin, as SphereFromOrigin.
class PostFromOrigin {
 public:
  PostFromOrigin(const glm::dvec3& origin, const glm::dvec2& axis_xy, double radius_m, double top_z)
      : origin_z_(origin.z),
        top_z_(top_z),
        axis_to_origin_xy_(origin.x - axis_xy.x, origin.y - axis_xy.y),
        offset_squared_minus_radius_squared_(glm::dot(axis_to_origin_xy_, axis_to_origin_xy_) - radius_m * radius_m) {}

  std::optional<double> intersect(const glm::dvec3& dir) const {
    const glm::dvec2 d{dir.x, dir.y};
    const double a = glm::dot(d, d);
    if (a < 1e-18) return std::nullopt;
    const double b = glm::dot(axis_to_origin_xy_, d);
    const double discriminant = b * b - a * offset_squared_minus_radius_squared_;
    if (discriminant < 0.0) return std::nullopt;
    const double root = std::sqrt(discriminant);
    for (double t : {(-b - root) / a, (-b + root) / a}) {
      if (t <= 1e-9) continue;
      const double z = origin_z_ + t * dir.z;
      if (z >= 0.0 && z <= top_z_) return t;
    }
    return std::nullopt;
  }

 private:
  double origin_z_, top_z_;
  glm::dvec2 axis_to_origin_xy_;  // origin.xy - axis_xy
  double offset_squared_minus_radius_squared_;
};

// Ray hits, t along origin + t * dir (dir unit length); nullopt on a miss.
inline std::optional<double> intersectSphere(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec3& center,
                                             double radius) {
  return SphereFromOrigin(origin, center, radius).intersect(dir);
}
// A vertical cylinder of radius_m around (axis_xy, z) for z in [0, top_z].
inline std::optional<double> intersectPost(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec2& axis_xy,
                                           double radius_m, double top_z) {
  return PostFromOrigin(origin, axis_xy, radius_m, top_z).intersect(dir);
}

// True when all four border corners project inside the image with margin_px to
// spare, and no point of the tag (border and a grid inside) hides behind the
// ball or its post as seen from the camera.
bool tagFullyVisible(const CameraIntrinsics& camera, const RigGeometry& rig, double post_radius_m,
                     const PoseCamFromWorld& pose, double margin_px = 0.0);

bool pointInImage(const CameraIntrinsics& camera, const glm::dvec2& p_px, double margin_px);

}  // namespace probelight::sim
