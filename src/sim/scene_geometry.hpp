// Geometry of the truth: where the tag's corners and the ball's outline land
// in the image (through OpenCV's camera model, distortion included), and
// whether they are in view and unoccluded.
#pragma once

#include <array>
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

// Ray hits, t along origin + t * dir (dir unit length); nullopt on a miss.
std::optional<double> intersectSphere(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec3& center,
                                      double radius);
// A vertical cylinder of radius_m around (axis_xy, z) for z in [0, top_z].
std::optional<double> intersectPost(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec2& axis_xy,
                                    double radius_m, double top_z);

// True when all four border corners project inside the image with margin_px to
// spare, and no point of the tag (border and a grid inside) hides behind the
// ball or its post as seen from the camera.
bool tagFullyVisible(const CameraIntrinsics& camera, const RigGeometry& rig, double post_radius_m,
                     const PoseCamFromWorld& pose, double margin_px = 0.0);

bool pointInImage(const CameraIntrinsics& camera, const glm::dvec2& p_px, double margin_px);

}  // namespace probelight::sim
