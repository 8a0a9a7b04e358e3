// Distant light around the scene: procedural skies and rooms, or a lat-long
// HDR photograph. Radiance is linear HDR in arbitrary units, per RGB channel.
#pragma once

#include <memory>
#include <string>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

namespace probelight::sim {

class Environment {
 public:
  virtual ~Environment() = default;
  // dir_w: unit direction in the world frame (+Z up), pointing away from the
  // scene toward the light.
  virtual glm::dvec3 radiance(const glm::dvec3& dir_w) const = 0;
  virtual std::string name() const = 0;
};

// Lat-long mapping used for HDR files (and documented for anyone writing one):
// u = (column + 0.5) / width, v = (row + 0.5) / height, both in [0, 1).
//   theta = v * pi              (angle from +Z: row 0 is the zenith, the middle row the horizon)
//   phi   = 2 pi (0.5 - u)      (azimuth from +X toward +Y)
//   dir   = (sin theta cos phi, sin theta sin phi, cos theta)
// So the image's centre column looks along +X, and moving right in the image
// turns right (toward -Y) as for a viewer standing inside the panorama: the
// picture is not mirrored. Both files in shared/data/env follow this (sky at
// the top).
glm::dvec2 latLongUvFromDirection(const glm::dvec3& dir_w);
glm::dvec3 directionFromLatLongUv(const glm::dvec2& uv);

// A lat-long RGB image sampled bilinearly (wrapping in u, clamped in v).
class LatLongEnvironment : public Environment {
 public:
  // rgb: CV_32FC3 in R,G,B order, width = 2 * height.
  LatLongEnvironment(cv::Mat rgb, std::string name);
  // Reads .hdr/.exr with cv::imread; throws SceneError naming the file.
  static std::unique_ptr<LatLongEnvironment> load(const std::string& path);

  glm::dvec3 radiance(const glm::dvec3& dir_w) const override;
  std::string name() const override { return name_; }

 private:
  cv::Mat rgb_;
  std::string name_;
};

// Procedural names (see environmentNames()):
//   uniform        L = 1 everywhere (for exact checks: E = pi L)
//   sun_sky        blue sky gradient + a 3 deg sun disc at azimuth -120 deg,
//                  elevation 40 deg whose irradiance is ~3x the sky's
//   sunrise        the same sky and sun, the sun 4 deg above the horizon
//   night_street   a dark sky (0.01) and facades (0.03) with two street
//                  lamps low over the street (2 deg discs at 8 and 15 deg
//                  elevation, 120 deg apart), each lighting a normal facing
//                  it like the night sky's whole hemisphere 30 times over
//   studio         dark room (0.02) with three soft boxes (key, fill, top)
//   overcast       CIE overcast sky, L = (1 + 2 cos theta) / 3, zenith 1
//   coloured_wall  neutral sky with a saturated red wall toward +X
// or a path to a .hdr/.exr lat-long file. Throws SceneError on anything else.
std::unique_ptr<Environment> makeEnvironment(const std::string& name_or_path);

}  // namespace probelight::sim
