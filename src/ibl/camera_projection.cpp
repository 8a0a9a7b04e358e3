#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

namespace {

// OpenCV's distortion of a normalised (x', y') point, term for term as in
// cv::projectPoints, so both agree to rounding.
glm::dvec2 distortNormalized(const CameraIntrinsics& camera, const glm::dvec2& p) {
  const auto& [k1, k2, p1, p2, k3] = camera.distortion;
  const double r2 = p.x * p.x + p.y * p.y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {p.x * radial + 2.0 * p1 * p.x * p.y + p2 * (r2 + 2.0 * p.x * p.x),
          p.y * radial + p1 * (r2 + 2.0 * p.y * p.y) + 2.0 * p2 * p.x * p.y};
}

}  // namespace

glm::dvec2 projectToPixel(const CameraIntrinsics& camera, const glm::dvec3& point_cam) {
  const glm::dvec2 distorted = distortNormalized(camera, {point_cam.x / point_cam.z, point_cam.y / point_cam.z});
  return {camera.fx_px * distorted.x + camera.cx_px, camera.fy_px * distorted.y + camera.cy_px};
}

glm::dvec3 pixelToCameraRay(const CameraIntrinsics& camera, const glm::dvec2& pixel) {
  const auto& [k1, k2, p1, p2, k3] = camera.distortion;
  const glm::dvec2 distorted{(pixel.x - camera.cx_px) / camera.fx_px, (pixel.y - camera.cy_px) / camera.fy_px};
  glm::dvec2 p = distorted;
  // Solve distort(p) = distorted as OpenCV's undistortPoints does:
  // p <- (distorted - tangential(p)) / radial(p).
  for (int i = 0; i < kUndistortIterations; ++i) {
    const double r2 = p.x * p.x + p.y * p.y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const glm::dvec2 tangential{2.0 * p1 * p.x * p.y + p2 * (r2 + 2.0 * p.x * p.x),
                                p1 * (r2 + 2.0 * p.y * p.y) + 2.0 * p2 * p.x * p.y};
    const glm::dvec2 next = (distorted - tangential) / radial;
    // Converged: the remaining error is about this step times the slope (< 1),
    // ~1e-11 px; a mild lens gets here in a few steps, not all of them.
    const bool converged = std::abs(next.x - p.x) + std::abs(next.y - p.y) < 1e-14;
    p = next;
    if (converged) break;
  }
  return {p.x, p.y, 1.0};
}

}  // namespace probelight::ibl
