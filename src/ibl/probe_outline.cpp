#include "ibl/probe_outline.hpp"

#include <cmath>
#include <vector>

#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

ProbeOutline computeProbeOutline(const MirrorBallView& view, int samples) {
  ProbeOutline outline;
  const glm::dvec3 center_cam = view.pose.toCamera(view.center_w);
  const double distance = glm::length(center_cam);
  const double radius = view.radius_m;
  // Written so that NaN or Inf (a degenerate pose, a bad rig) fails too: an
  // outline with a NaN centre must not come out valid.
  if (samples < 8 || !(radius > 0.0) || !std::isfinite(radius) || !std::isfinite(distance) ||
      !(distance > radius * 1.0001))
    return outline;

  // Tangency circle: centre on the line of sight at distance (d^2 - r^2)/d,
  // radius r * sqrt(d^2 - r^2) / d.
  const glm::dvec3 axis = center_cam / distance;
  const double along = (distance * distance - radius * radius) / distance;
  const double circle_radius = radius * std::sqrt(distance * distance - radius * radius) / distance;
  const glm::dvec3 helper = std::abs(axis.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  const glm::dvec3 u = glm::normalize(glm::cross(axis, helper));
  const glm::dvec3 v = glm::cross(axis, u);

  std::vector<glm::dvec2> points(static_cast<size_t>(samples));
  for (int i = 0; i < samples; ++i) {
    const double angle = 2.0 * M_PI * i / samples;
    const glm::dvec3 p = axis * along + circle_radius * (std::cos(angle) * u + std::sin(angle) * v);
    if (!(p.z > 1e-9)) return outline;  // part of the outline is behind the camera
    points[static_cast<size_t>(i)] = projectToPixel(view.camera, p);
    // Non-finite intrinsics give non-finite points: no outline.
    if (!std::isfinite(points[static_cast<size_t>(i)].x) || !std::isfinite(points[static_cast<size_t>(i)].y))
      return outline;
  }

  double twice_area = 0.0;
  glm::dvec2 centroid_sum{0.0};
  outline.min_px = outline.max_px = points[0];
  for (int i = 0; i < samples; ++i) {
    const glm::dvec2& a = points[static_cast<size_t>(i)];
    const glm::dvec2& b = points[static_cast<size_t>((i + 1) % samples)];
    const double cross = a.x * b.y - b.x * a.y;
    twice_area += cross;
    centroid_sum += (a + b) * cross;
    outline.min_px = glm::min(outline.min_px, a);
    outline.max_px = glm::max(outline.max_px, a);
  }
  if (!(std::abs(twice_area) >= 1e-12) || !std::isfinite(twice_area)) return outline;
  outline.center_px = centroid_sum / (3.0 * twice_area);
  outline.radius_px = std::sqrt(std::abs(twice_area) * 0.5 / M_PI);
  outline.fully_in_image = outline.min_px.x >= 0.0 && outline.min_px.y >= 0.0 &&
                           outline.max_px.x <= view.camera.width_px - 1.0 &&
                           outline.max_px.y <= view.camera.height_px - 1.0;
  outline.polygon_px = std::move(points);
  outline.valid = true;
  return outline;
}

}  // namespace probelight::ibl
