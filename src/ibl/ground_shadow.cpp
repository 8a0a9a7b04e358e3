#include "ibl/ground_shadow.hpp"
#include "core/math_constants.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace probelight::ibl {

namespace {

bool finiteVector(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Two unit vectors perpendicular to d and to each other.
void basisAround(const glm::dvec3& d, glm::dvec3& a, glm::dvec3& b) {
  const glm::dvec3 helper = std::abs(d.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
  a = glm::normalize(glm::cross(helper, d));
  b = glm::cross(d, a);
}

}  // namespace

glm::dvec3 ShadowCaster::boundingCentre() const {
  if (shape == Shape::kSphere) return {position_w.x, position_w.y, radius_m};
  if (shape == Shape::kMesh) return mesh_centre_w;
  return {position_w.x, position_w.y, 0.5 * box_size_m.z};
}

double ShadowCaster::boundingRadius() const {
  if (shape == Shape::kSphere) return radius_m;
  if (shape == Shape::kMesh) return mesh_radius_m;
  return 0.5 * glm::length(box_size_m);
}

std::optional<double> ShadowCaster::intersect(const glm::dvec3& origin, const glm::dvec3& dir) const {
  if (shape == Shape::kSphere) {
    const glm::dvec3 oc = origin - boundingCentre();
    const double b = glm::dot(oc, dir);
    const double c = glm::dot(oc, oc) - radius_m * radius_m;
    const double discriminant = b * b - c;
    if (!(discriminant >= 0.0)) return std::nullopt;
    const double root = std::sqrt(discriminant);
    if (-b - root > 0.0) return -b - root;
    if (-b + root > 0.0) return -b + root;
    return std::nullopt;
  }
  if (shape == Shape::kMesh) {
    // The CPU reference only (the GPU renders the triangles): the bounding
    // sphere first, then every triangle (Moller-Trumbore, both faces).
    const glm::dvec3 oc = origin - mesh_centre_w;
    const double b = glm::dot(oc, dir);
    const double c = glm::dot(oc, oc) - mesh_radius_m * mesh_radius_m;
    if (!(b * b - c >= 0.0) || (c > 0.0 && b > 0.0) || !mesh_triangles_w) return std::nullopt;
    std::optional<double> nearest;
    const std::vector<glm::vec3>& triangles = *mesh_triangles_w;
    for (std::size_t i = 0; i + 2 < triangles.size(); i += 3) {
      const glm::dvec3 a(triangles[i]), e1 = glm::dvec3(triangles[i + 1]) - a, e2 = glm::dvec3(triangles[i + 2]) - a;
      const glm::dvec3 p = glm::cross(dir, e2);
      const double det = glm::dot(e1, p);
      if (std::abs(det) < 1e-300) continue;
      const glm::dvec3 s = origin - a;
      const double u = glm::dot(s, p) / det;
      if (u < 0.0 || u > 1.0) continue;
      const glm::dvec3 q = glm::cross(s, e1);
      const double v = glm::dot(dir, q) / det;
      if (v < 0.0 || u + v > 1.0) continue;
      const double t = glm::dot(e2, q) / det;
      if (t > 0.0 && (!nearest || t < *nearest)) nearest = t;
    }
    return nearest;
  }
  // Slabs in the box's own frame (turned by yaw about +Z, centred at its middle).
  const double c = std::cos(box_yaw_rad), s = std::sin(box_yaw_rad);
  const glm::dvec3 centre = boundingCentre();
  const glm::dvec3 o = origin - centre;
  const glm::dvec3 local_origin(c * o.x + s * o.y, -s * o.x + c * o.y, o.z);
  const glm::dvec3 local_dir(c * dir.x + s * dir.y, -s * dir.x + c * dir.y, dir.z);
  double t_near = -std::numeric_limits<double>::infinity(), t_far = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    const double half = 0.5 * box_size_m[axis];
    if (std::abs(local_dir[axis]) < 1e-15) {
      if (std::abs(local_origin[axis]) > half) return std::nullopt;
      continue;
    }
    double t0 = (-half - local_origin[axis]) / local_dir[axis];
    double t1 = (half - local_origin[axis]) / local_dir[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return std::nullopt;
  }
  if (t_near > 0.0) return t_near;
  if (t_far > 0.0) return t_far;
  return std::nullopt;
}

double coneRadiusFor(const DomeLight& light, double min_cone_rad) {
  const double cone = std::sqrt(2.0) * light.spread_rad;
  return std::isfinite(cone) ? std::max(cone, min_cone_rad) : min_cone_rad;
}

std::vector<ShadowLight> groundShadowLights(const std::vector<DomeLight>& dome, double min_share) {
  glm::dvec3 total(0.0);
  for (const DomeLight& light : dome)
    if (finiteVector(light.rgb) && finiteVector(light.direction_w))
      total += glm::max(light.rgb, glm::dvec3(0.0)) * std::max(0.0, light.direction_w.z);
  std::vector<ShadowLight> lights;
  if (!(std::max({total.r, total.g, total.b}) > 0.0)) return lights;
  for (const DomeLight& light : dome) {
    if (!finiteVector(light.rgb) || !finiteVector(light.direction_w) || !(light.direction_w.z > 0.0)) continue;
    ShadowLight shadow;
    shadow.direction_w = glm::normalize(light.direction_w);
    shadow.rgb = glm::max(light.rgb, glm::dvec3(0.0));
    for (int c = 0; c < 3; ++c)
      shadow.share_rgb[c] = total[c] > 0.0 ? std::max(0.0, light.rgb[c]) * light.direction_w.z / total[c] : 0.0;
    if (!(std::max({shadow.share_rgb.r, shadow.share_rgb.g, shadow.share_rgb.b}) >= min_share)) continue;
    // The sharpest shadow: a quarter of a degree, the sun's radius.
    shadow.cone_radius_rad = coneRadiusFor(light, 0.25 * kPi / 180.0);
    lights.push_back(shadow);
  }
  return lights;
}

GroundRegion groundShadowRegion(const ShadowCaster& caster, const std::vector<ShadowLight>& lights,
                                double max_half_size_m) {
  GroundRegion region;
  const glm::dvec3 centre = caster.boundingCentre();
  const double radius = caster.boundingRadius();
  region.centre_w = glm::dvec2(centre);
  double reach = radius;
  for (const ShadowLight& light : lights) {
    // The lowest direction of the light's cone casts the longest shadow:
    // the bounding sphere's top, cast down along it, lands this far away
    // horizontally, plus the sphere's own radius across.
    const double elevation = std::asin(std::clamp(light.direction_w.z, -1.0, 1.0)) - light.cone_radius_rad;
    const double top = centre.z + radius;
    const double length = elevation > 1e-6 ? top / std::tan(elevation) : std::numeric_limits<double>::infinity();
    reach = std::max(reach, length + radius);
  }
  region.half_size_m = std::min(reach * 1.05, max_half_size_m);
  return region;
}

glm::dvec3 groundLightFraction(const glm::dvec2& p_w, const ShadowCaster& caster,
                               const std::vector<ShadowLight>& lights, int samples) {
  glm::dvec3 fraction(1.0);
  const glm::dvec3 p(p_w, 0.0);
  const int per_axis = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(samples)))));
  for (const ShadowLight& light : lights) {
    double hidden = 0.0;
    if (light.cone_radius_rad <= 0.0) {
      hidden = caster.intersect(p, light.direction_w) ? 1.0 : 0.0;
    } else {
      // Stratified over the cone: equal-area rings (cos uniform) and sectors,
      // one sample at each cell's centre: deterministic.
      glm::dvec3 a, b;
      basisAround(light.direction_w, a, b);
      const double cos_max = std::cos(light.cone_radius_rad);
      int count = 0, blocked = 0;
      for (int i = 0; i < per_axis; ++i)
        for (int j = 0; j < per_axis; ++j) {
          const double cos_theta = 1.0 - (1.0 - cos_max) * (i + 0.5) / per_axis;
          const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
          const double phi = 2.0 * kPi * (j + 0.5 * (i % 2) + 0.5) / per_axis;
          const glm::dvec3 dir = cos_theta * light.direction_w + sin_theta * (std::cos(phi) * a + std::sin(phi) * b);
          ++count;
          if (dir.z > 0.0 && caster.intersect(p, dir)) ++blocked;
        }
      hidden = static_cast<double>(blocked) / count;
    }
    fraction -= hidden * light.share_rgb;
  }
  return glm::clamp(fraction, glm::dvec3(0.0), glm::dvec3(1.0));
}

glm::dvec3 compositeByRatio(const glm::dvec3& camera_linear, const glm::dvec3& fraction) {
  return camera_linear * fraction;
}

glm::dvec3 compositeBySubtraction(const glm::dvec3& camera_linear, const glm::dvec3& fraction,
                                  const glm::dvec3& white_floor_linear) {
  return glm::max(camera_linear - (glm::dvec3(1.0) - fraction) * white_floor_linear, glm::dvec3(0.0));
}

}  // namespace probelight::ibl
