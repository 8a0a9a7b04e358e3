#include "ibl/near_floor.hpp"

#include <algorithm>

#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

NearFloorLookup nearFloorLookup(const glm::vec3& point_w, const glm::vec3& direction_w, const NearFloorBall& ball) {
  NearFloorLookup lookup;
  lookup.map_direction_w = direction_w;
  if (!(direction_w.z < 0.0f)) return lookup;
  // A point a rounding error below the ground is on it.
  const float height_m = std::max(point_w.z, 0.0f);
  const float distance_m = std::min(height_m / -direction_w.z, kNearFloorMaxDistance_m);
  lookup.meets_ground = true;
  lookup.ground_point_w = point_w + distance_m * direction_w;
  lookup.ground_point_w.z = 0.0f;
  glm::vec3 from_ball = lookup.ground_point_w - ball.centre_w;
  float length = glm::length(from_ball);
  // The ball's centre on the ground itself (no rig puts it there): the ray's own direction.
  if (!(length > 1e-3f)) return lookup;
  glm::vec3 d = from_ball / length;
  for (int step = 0; step < kNearFloorBallSteps; ++step) {
    const glm::vec3 half = d + ball.to_eye_w;
    const float half_length = glm::length(half);
    // d straight away from the camera: the ball's rim, where any normal on it will do.
    if (!(half_length > 1e-3f)) break;
    from_ball = lookup.ground_point_w - (ball.centre_w + ball.radius_m * half / half_length);
    length = glm::length(from_ball);
    if (!(length > 1e-3f)) break;
    d = from_ball / length;
  }
  lookup.map_direction_w = d;
  return lookup;
}

float cameraFloorWeight(const glm::vec2& pixel, int width_px, int height_px) {
  // The outermost pixels' centres are half a pixel inside the edge.
  const float inside_px = std::min(std::min(pixel.x + 0.5f, static_cast<float>(width_px) - 0.5f - pixel.x),
                                   std::min(pixel.y + 0.5f, static_cast<float>(height_px) - 0.5f - pixel.y));
  return std::clamp(inside_px / kCameraFloorMarginPx, 0.0f, 1.0f);
}

double cameraFloorReach2(const CameraIntrinsics& camera) {
  double reach2 = 0.0;
  for (const glm::dvec2 pixel : {glm::dvec2(-0.5, -0.5), glm::dvec2(camera.width_px - 0.5, -0.5),
                                 glm::dvec2(-0.5, camera.height_px - 0.5),
                                 glm::dvec2(camera.width_px - 0.5, camera.height_px - 0.5)}) {
    const glm::dvec3 ray = pixelToCameraRay(camera, pixel);
    reach2 = std::max(reach2, ray.x * ray.x + ray.y * ray.y);
  }
  return 2.25 * reach2;
}

}  // namespace probelight::ibl
