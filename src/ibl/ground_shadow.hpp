// Shadows of a virtual object on the real ground, from the dome of lights:
// the model the GPU pass (passes/ground_shadow.hpp) implements, and its
// CPU reference.
//
// The real ground is a phantom: it gets no virtual light, only the share of
// its real light that the object takes away. With E the ground's irradiance
// (upper hemisphere, n = +Z) and R = sum_i C_i (N . L_i) (1 - S_i) what the
// object blocks, the camera pixel is multiplied by (E - R) / E (ratio-form
// differential rendering): the floor darkens by the right fraction whatever
// its albedo or colour. Seed B subtracted R from the pixel instead, which is
// right only for a white floor: a dark floor goes black, a coloured one
// changes hue (compositeBySubtraction, kept for the test that shows it).
//
// Each dome light is a uniform cone of directions of half-angle
// cone_radius_rad around its direction (its region's light, spread as the
// region's energy is), so its shadow is soft by as much as the region is
// wide. The fraction of one light that reaches a ground point is the share
// of its cone the object does not hide.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "ibl/light_dome.hpp"

namespace probelight::ibl {

// A virtual object standing on the ground (z = 0) of W.
struct ShadowCaster {
  enum class Shape { kSphere, kBox, kMesh };
  Shape shape = Shape::kSphere;
  glm::dvec2 position_w{0.0};               // where it stands
  double radius_m = 0.035;                  // sphere: centre at z = radius
  glm::dvec3 box_size_m{0.05, 0.05, 0.05};  // box: full edges along its own x, y, z; bottom face on the ground
  double box_yaw_rad = 0.0;                 // box: turned about +Z
  // mesh: a user's model, placed: triangles in W (3 vertices each, as
  // wound), and a sphere around them all (model::placedBoundingSphere).
  // Shared, not copied: a model may have a million triangles.
  std::shared_ptr<const std::vector<glm::vec3>> mesh_triangles_w;
  glm::dvec3 mesh_centre_w{0.0};
  double mesh_radius_m = 0.0;

  glm::dvec3 boundingCentre() const;
  double boundingRadius() const;
  // Nearest hit t > 0 along origin + t dir (dir unit), if any.
  std::optional<double> intersect(const glm::dvec3& origin, const glm::dvec3& dir) const;
};

// One dome light as the ground shadow uses it.
struct ShadowLight {
  glm::dvec3 direction_w{0.0, 0.0, 1.0};
  glm::dvec3 share_rgb{0.0};  // C_i (N . L_i) / E per channel: its share of the ground's irradiance
  double cone_radius_rad = 0.0;
  glm::dvec3 rgb{0.0};  // C_i: the dome light's irradiance at normal incidence (the object's self-shadow weighs by it)
};

// The dome's lights that can darken the ground: above the horizon, and with
// a share of at least min_share in some channel (1/255 by default: a light
// that cannot move an 8-bit pixel by one code even when wholly hidden casts
// no visible shadow). Shares are of the dome's own E = sum C_i max(0, L_i.z),
// which the dome reproduces exactly (light_dome.hpp). None when E is 0.
std::vector<ShadowLight> groundShadowLights(const std::vector<DomeLight>& dome, double min_share = 1.0 / 255.0);

// The cone half-angle for a dome light: its region's half-energy angle
// times sqrt(2), the radius of the uniform disc with that half-energy
// angle; at least min_cone_rad (the sharpest shadow the maps resolve).
double coneRadiusFor(const DomeLight& light, double min_cone_rad);

// The square of ground, centred under the object, that the shadows can
// reach: the object's bounding sphere cast along every light (at most
// max_half_size_m from the object, for lights near the horizon, whose
// shadows run out to infinity).
struct GroundRegion {
  glm::dvec2 centre_w{0.0};
  double half_size_m = 0.0;
};
GroundRegion groundShadowRegion(const ShadowCaster& caster, const std::vector<ShadowLight>& lights,
                                double max_half_size_m);

// The CPU reference: the fraction of the ground's irradiance that reaches
// ground point p (1 = unshadowed), per channel: 1 - sum_i share_i B_i with
// B_i the hidden share of light i's cone, sampled with `samples` stratified
// directions over the cone (and exactly 0 or 1 for a cone of zero width).
glm::dvec3 groundLightFraction(const glm::dvec2& p_w, const ShadowCaster& caster,
                               const std::vector<ShadowLight>& lights, int samples = 256);

// Compositing a shadowed real pixel, in linear light.
// Ratio form (what probelight does): pixel * fraction.
glm::dvec3 compositeByRatio(const glm::dvec3& camera_linear, const glm::dvec3& fraction);
// Seed B: pixel - R, with R expressed in pixel units as a white (albedo 1)
// Lambertian floor would see it: (1 - fraction) * white_floor_linear. Right
// only when the floor is white.
glm::dvec3 compositeBySubtraction(const glm::dvec3& camera_linear, const glm::dvec3& fraction,
                                  const glm::dvec3& white_floor_linear);

}  // namespace probelight::ibl
