#include "ibl/probe_observation.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>

#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

namespace {

// A uniform pixel's position variance, px^2.
constexpr double kPixelFootprintVariancePx2 = 1.0 / 12.0;

double meanFocalPx(const CameraIntrinsics& camera) { return 0.5 * (camera.fx_px + camera.fy_px); }

// The ball's image radius: the tangent cone's, f R / sqrt(D^2 - R^2).
double ballRadiusPx(const MirrorBallView& view, double distance_m) {
  const double r = view.radius_m;
  if (!(distance_m > r)) return 0.0;
  return meanFocalPx(view.camera) * r / std::sqrt(distance_m * distance_m - r * r);
}

double texelAngleRad(int face_size) { return 0.5 * std::numbers::pi / face_size; }

// Distance from point p to the segment a..b.
double distanceToSegment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double length2 = glm::dot(ab, ab);
  const double t = length2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / length2, 0.0, 1.0) : 0.0;
  return glm::length(a + t * ab - p);
}

// Whether the segment a..b passes within `radius` of the vertical axis
// through (axis_xy) between heights z0 and z1: a post.
bool segmentNearPost(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec2& axis_xy, double z0, double z1,
                     double radius) {
  // Sampled along the segment's part between the heights: the post is thin
  // and the test conservative at the sample spacing (radius / 2).
  const double length = glm::length(b - a);
  const int steps = std::clamp(static_cast<int>(length / std::max(0.5 * radius, 1e-4)), 2, 4000);
  for (int i = 0; i <= steps; ++i) {
    const glm::dvec3 p = a + (b - a) * (static_cast<double>(i) / steps);
    if (p.z < z0 || p.z > z1) continue;
    if (glm::length(glm::dvec2(p) - axis_xy) < radius) return true;
  }
  return false;
}

struct FrameGeometry {
  glm::dvec3 eye_w;           // camera centre
  double ball_depth_m = 0.0;  // the ball centre's camera z
  double margin_m = 0.0;      // exclusion_margin_px at the ball's depth
  glm::dvec2 extent_normalized{0.0};  // |x/z|, |y/z| the frame reaches (undistorted)
};

}  // namespace

namespace {

// What ballSampleConfidence needs of a view, worked out once per view.
struct BallSight {
  explicit BallSight(const MirrorBallView& view) {
    const glm::dvec3 to_eye = view.pose.cameraCenterWorld() - view.center_w;
    const double distance = glm::length(to_eye);
    radius_px = ballRadiusPx(view, distance);
    if (radius_px > 0.0) {
      eye_direction = to_eye / distance;
      eye_in_radii = to_eye / view.radius_m;
    }
  }

  double confidence(const glm::dvec3& r_w, double texel_angle_rad, const ObservationSettings& settings) const {
    if (!(radius_px > 0.0)) return 0.0;
    const glm::dvec3 bisector = eye_direction + r_w;
    const double length = glm::length(bisector);
    if (!(length > 1e-9)) return 0.0;
    // The normal that reflects the eye into r (the orthographic bisector; at
    // kiosk distances, 15-30 radii, perspective moves it by under a degree).
    // The eye sees it only where it faces the eye from the surface point (in
    // ball radii: n . (E - n) > 0), which perspective narrows to a cone; the
    // incidence there is against the surface point's own line of sight.
    const glm::dvec3 normal = bisector / length;
    const glm::dvec3 eye_from_point = eye_in_radii - normal;
    const double cos_incidence = glm::dot(normal, eye_from_point) / glm::length(eye_from_point);
    if (!(cos_incidence > 0.0)) return 0.0;
    const double sin_incidence = std::sqrt(std::max(0.0, 1.0 - cos_incidence * cos_incidence));
    // Image radius R sin(theta) turns into 2 theta of reflected direction.
    const double rad_per_px = 2.0 / (radius_px * cos_incidence);
    const double to_edge_px = radius_px * (1.0 - sin_incidence);
    const double mix_px = std::max(0.0, settings.edge_mix_px - to_edge_px);
    const double pixel_variance =
        kPixelFootprintVariancePx2 + settings.pose_sigma_px * settings.pose_sigma_px + mix_px * mix_px;
    const double variance = pixel_variance * rad_per_px * rad_per_px + texel_angle_rad * texel_angle_rad / 12.0;
    return 1.0 / variance;
  }

  double radius_px = 0.0;
  glm::dvec3 eye_direction{0.0};
  glm::dvec3 eye_in_radii{0.0};
};

// BallSight::confidence depends on r only through u = n . v =
// sqrt((1 + r . v) / 2), the cosine of the angle between the reflecting
// normal and the eye: tabulated once per view in bins even in u (fine at
// the rim, where it falls fastest) and read linearly between them, so that
// each texel costs a dot product instead of a chain of roots and divisions.
class ConfidenceByHalfAngle {
 public:
  ConfidenceByHalfAngle(const BallSight& sight, double texel_angle_rad, const ObservationSettings& settings)
      : eye_direction_(sight.eye_direction), table_(kBins + 2, 0.0f) {
    // A direction with half-angle cosine u: rotate v by 2 acos(u) about any axis.
    const glm::dvec3 v = sight.eye_direction;
    const glm::dvec3 helper = std::abs(v.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
    const glm::dvec3 across = glm::normalize(glm::cross(v, helper));
    for (int bin = 0; bin <= kBins; ++bin) {
      const double u = static_cast<double>(bin) / kBins;
      const double angle = 2.0 * std::acos(std::clamp(u, 0.0, 1.0));
      const glm::dvec3 r = std::cos(angle) * v + std::sin(angle) * across;
      table_[static_cast<std::size_t>(bin)] = static_cast<float>(sight.confidence(r, texel_angle_rad, settings));
    }
    table_[kBins + 1] = table_[kBins];
  }

  double operator()(const glm::dvec3& r_w) const {
    const double u = std::sqrt(std::max(0.0, 0.5 * (1.0 + glm::dot(r_w, eye_direction_))));
    const double position = std::min(u, 1.0) * kBins;
    const int bin = static_cast<int>(position);
    const double t = position - bin;
    // Zero at either end of the bin: the direction may be out of the
    // ball's sight (the table's zero), and a blend would make it seen.
    const float a = table_[static_cast<std::size_t>(bin)], b = table_[static_cast<std::size_t>(bin) + 1];
    if (!(a > 0.0f) || !(b > 0.0f)) return 0.0;
    return a + t * (b - a);
  }

 private:
  static constexpr int kBins = 1024;
  glm::dvec3 eye_direction_;
  std::vector<float> table_;
};

}  // namespace

const std::vector<glm::vec3>& texelDirections(int n) {
  static std::mutex guard;
  static std::map<int, std::vector<glm::vec3>> by_size;
  const std::lock_guard<std::mutex> lock(guard);
  auto found = by_size.find(n);
  if (found != by_size.end()) return found->second;
  std::vector<glm::vec3> directions(static_cast<std::size_t>(kCubeFaceCount) * n * n);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        directions[(static_cast<std::size_t>(face) * n + y) * n + x] = glm::vec3(cubeTexelCenterDirection(face, x, y, n));
  return by_size.emplace(n, std::move(directions)).first->second;
}

double ballSampleConfidence(const MirrorBallView& view, const glm::dvec3& r_w, double texel_angle_rad,
                            const ObservationSettings& settings) {
  return BallSight(view).confidence(r_w, texel_angle_rad, settings);
}

ProbeObservation observeBall(const MirrorBallView& view, const CubeMapRGB& map, const std::vector<float>* validity,
                             const std::vector<std::uint8_t>* still_clipped, double clip_level,
                             const ObservationSettings& settings) {
  ProbeObservation observation(map.face_size);
  observeBall(view, map, validity, still_clipped, clip_level, settings, observation);
  return observation;
}

void observeBall(const MirrorBallView& view, const CubeMapRGB& map, const std::vector<float>* validity,
                 const std::vector<std::uint8_t>* still_clipped, double clip_level, const ObservationSettings& settings,
                 ProbeObservation& observation) {
  const int n = map.face_size;
  observation.reset(n);
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  const bool have_flags = still_clipped != nullptr && still_clipped->size() == observation.texelCount();
  const double texel_angle = texelAngleRad(n);
  const BallSight sight(view);
  const ConfidenceByHalfAngle confidenceOf(sight, texel_angle, settings);
  const std::vector<glm::vec3>& directions = texelDirections(n);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (std::size_t local = 0; local < per_face; ++local) {
      const std::size_t i = static_cast<std::size_t>(face) * per_face + local;
      if (!texelSeen(validity, face, local, n)) continue;
      const glm::vec3 value = map.faces[face][local];
      if (!std::isfinite(value.x) || !std::isfinite(value.y) || !std::isfinite(value.z)) continue;
      const glm::dvec3 direction(directions[i]);
      // Without a validity, the ball's own test of what it shows (the map
      // holds 0 there, which is no measurement).
      if (validity == nullptr && !reflectedDirectionToPixel(view, direction, 1)) continue;
      const double confidence = confidenceOf(direction);
      if (!(confidence > 0.0)) continue;
      observation.radiance.faces[face][local] = value;
      observation.confidence[i] = static_cast<float>(confidence);
      observation.lower_bound[i] = have_flags ? (*still_clipped)[i]
                                              : static_cast<std::uint8_t>(std::max({value.x, value.y, value.z}) >=
                                                                          static_cast<float>(clip_level));
      observation.source[i] = 1;
    }
}

long addFrameAroundBall(ProbeObservation& observation, const MirrorBallView& view, const RigGeometry& rig,
                        const LinearPixelReader& read, const ObservationSettings& settings) {
  if (!settings.use_frame || !read) return 0;
  const CameraIntrinsics& camera = view.camera;
  FrameGeometry geometry;
  geometry.eye_w = view.pose.cameraCenterWorld();
  geometry.ball_depth_m = view.pose.toCamera(view.center_w).z;
  if (!(geometry.ball_depth_m > view.radius_m)) return 0;
  const double focal_px = meanFocalPx(camera);
  geometry.margin_m = settings.exclusion_margin_px * geometry.ball_depth_m / focal_px;
  // The undistorted extent of the frame: a direction beyond it can fold
  // back into the image through the distortion polynomial.
  for (const glm::dvec2 corner : {glm::dvec2(0.0, 0.0), glm::dvec2(camera.width_px - 1.0, 0.0),
                                  glm::dvec2(0.0, camera.height_px - 1.0),
                                  glm::dvec2(camera.width_px - 1.0, camera.height_px - 1.0)}) {
    const glm::dvec3 ray = pixelToCameraRay(camera, corner);
    geometry.extent_normalized = glm::max(geometry.extent_normalized, glm::abs(glm::dvec2(ray)));
  }
  const glm::dvec3 ball = view.center_w;
  const bool has_post = rig.post_radius_m > 0.0 && ball.z - view.radius_m > 0.0;
  const double post_top = ball.z - view.radius_m;
  const double ball_clearance = view.radius_m + geometry.margin_m;
  const double post_clearance = rig.post_radius_m + geometry.margin_m;

  // The pixel showing camera-frame point p (a direction when `direction`),
  // if the frame shows it.
  auto pixelOf = [&](const glm::dvec3& p_cam) -> std::optional<glm::dvec2> {
    if (!(p_cam.z > 1e-6)) return std::nullopt;
    const glm::dvec2 normalized(p_cam.x / p_cam.z, p_cam.y / p_cam.z);
    if (std::abs(normalized.x) > geometry.extent_normalized.x || std::abs(normalized.y) > geometry.extent_normalized.y)
      return std::nullopt;
    const glm::dvec2 pixel = projectToPixel(camera, p_cam);
    if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y) || pixel.x < 0.0 || pixel.y < 0.0 ||
        pixel.x > camera.width_px - 1.0 || pixel.y > camera.height_px - 1.0)
      return std::nullopt;
    return pixel;
  };
  // The camera's line of sight to a world point (or far along a direction)
  // is clear of the ball and the post.
  auto sightClear = [&](const glm::dvec3& far_w) {
    if (distanceToSegment(ball, geometry.eye_w, far_w) < ball_clearance) return false;
    if (has_post && segmentNearPost(geometry.eye_w, far_w, glm::dvec2(ball), 0.0, post_top, post_clearance))
      return false;
    return true;
  };
  auto bilinear = [&](const glm::dvec2& pixel, bool& clipped) {
    const int x0 = std::min(static_cast<int>(std::floor(pixel.x)), camera.width_px - 2);
    const int y0 = std::min(static_cast<int>(std::floor(pixel.y)), camera.height_px - 2);
    const double fx = pixel.x - x0, fy = pixel.y - y0;
    glm::dvec3 sum(0.0);
    clipped = false;
    for (int dy = 0; dy <= 1; ++dy)
      for (int dx = 0; dx <= 1; ++dx) {
        bool pixel_clipped = false;
        const glm::dvec3 value = read(x0 + dx, y0 + dy, pixel_clipped);
        clipped = clipped || pixel_clipped;
        sum += value * ((dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy));
      }
    return sum;
  };

  const int n = observation.face_size();
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  const double texel_variance = texelAngleRad(n) * texelAngleRad(n) / 12.0;
  const double pixel_variance = kPixelFootprintVariancePx2 + settings.pose_sigma_px * settings.pose_sigma_px;
  const glm::dvec3 baseline = geometry.eye_w - ball;
  long given = 0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (std::size_t local = 0; local < per_face; ++local) {
      const std::size_t i = static_cast<std::size_t>(face) * per_face + local;
      const int x = static_cast<int>(local) % n, y = static_cast<int>(local) / n;
      // Only what the ball does not show at all: a rim sample, however
      // unsure of its direction, holds the light it saw (a sun squeezed
      // into the rim spreads over many texels, its energy kept), which a
      // sharp sample of part of the same directions would take away.
      if (observation.confidence[i] > 0.0f) continue;
      const glm::dvec3 r = cubeTexelCenterDirection(face, x, y, n);
      std::optional<glm::dvec2> pixel;
      double variance = 0.0;
      double light_distance_m = settings.background_min_distance_m;  // from the ball, for the parallax
      if (r.z < -1e-6 && ball.z > 0.0) {
        // The ground point the ball sees along r, read where the camera sees it.
        const double t = -ball.z / r.z;
        const glm::dvec3 ground = ball + t * r;
        light_distance_m = t;
        pixel = pixelOf(view.pose.toCamera(ground));
        if (pixel && sightClear(ground)) {
          // Pixels per radian of r there (a lower bound): the ground point
          // moves t per radian across r and more along the slope, seen from
          // the camera at its depth and foreshortened by its grazing angle.
          const glm::dvec3 to_ground = ground - geometry.eye_w;
          const double depth = glm::length(to_ground);
          const double grazing = std::abs(to_ground.z) / depth;
          const double px_per_rad = focal_px * t * grazing / depth;
          if (!(px_per_rad > 0.0)) continue;
          variance = pixel_variance / (px_per_rad * px_per_rad) + texel_variance;
        } else {
          pixel.reset();  // the ball (or the post) hides that ground point from the camera
        }
      }
      if (!pixel) {
        // The camera's own ray along r: the same direction, from a point
        // |b x r| to the side, so the light it meets at distance d from the
        // ball is seen |b x r| / d off (d: the ground point's distance
        // below the horizon, the room's assumed least above it).
        const double reach_m = r.z < -1e-6 ? geometry.eye_w.z / -r.z : settings.background_min_distance_m + glm::length(baseline);
        pixel = pixelOf(view.pose.R_cam_from_world * r);
        if (!pixel || !sightClear(geometry.eye_w + r * reach_m)) continue;
        const double parallax_rad = glm::length(glm::cross(baseline, r)) / light_distance_m;
        variance = parallax_rad * parallax_rad + pixel_variance / (focal_px * focal_px) + texel_variance;
      }
      const double confidence = 1.0 / variance;
      bool clipped = false;
      const glm::dvec3 value = bilinear(*pixel, clipped);
      if (!std::isfinite(value.x) || !std::isfinite(value.y) || !std::isfinite(value.z)) continue;
      observation.radiance.faces[face][local] = glm::vec3(value);
      observation.confidence[i] = static_cast<float>(confidence);
      observation.lower_bound[i] = clipped ? 1 : 0;
      observation.source[i] = 2;
      ++given;
    }
  return given;
}

}  // namespace probelight::ibl
