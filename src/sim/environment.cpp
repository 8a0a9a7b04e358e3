#include "sim/environment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <utility>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/math_constants.hpp"
#include "sim/scene_config.hpp"

namespace probelight::sim {
namespace {

glm::dvec3 directionFromAzimuthElevation(double azimuth_rad, double elevation_rad) {
  return {std::cos(elevation_rad) * std::cos(azimuth_rad), std::cos(elevation_rad) * std::sin(azimuth_rad),
          std::sin(elevation_rad)};
}

// Smooth 0..1 ramp, so lights have soft edges a finite grid can integrate.
double smoothEdge(double inside_distance, double softness) {
  double x = std::clamp(inside_distance / softness + 0.5, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

class UniformEnvironment : public Environment {
 public:
  glm::dvec3 radiance(const glm::dvec3&) const override { return glm::dvec3(1.0); }
  std::string name() const override { return "uniform"; }
};

class SunSkyEnvironment : public Environment {
 public:
  explicit SunSkyEnvironment(double sun_elevation_deg = 40.0, std::string name = "sun_sky")
      : sun_dir_(directionFromAzimuthElevation(degToRad(-120.0), degToRad(sun_elevation_deg))), name_(std::move(name)) {
    // Sun irradiance at normal incidence = 3 pi (about 3x the sky's E_up).
    double disc_solid_angle = 2.0 * kPi * (1.0 - std::cos(kSunRadiusRad));
    sun_radiance_ = 3.0 * kPi / disc_solid_angle;
  }
  glm::dvec3 radiance(const glm::dvec3& dir) const override {
    double elevation = std::max(0.0, dir.z);
    glm::dvec3 horizon{0.85, 0.9, 1.0};
    glm::dvec3 zenith{0.3, 0.5, 1.0};
    double t = std::sqrt(elevation);
    glm::dvec3 sky = (1.0 - t) * horizon + t * zenith;
    // The cosine first: acos only for the few directions near the sun.
    const double cos_angle = std::clamp(glm::dot(dir, sun_dir_), -1.0, 1.0);
    if (cos_angle <= cos_outer_edge_) return sky;
    double angle = std::acos(cos_angle);
    if (angle < kSunRadiusRad + kSunLimbRad) {
      double weight = smoothEdge(kSunRadiusRad - angle, 2.0 * kSunLimbRad);
      sky += weight * sun_radiance_ * glm::dvec3(1.0, 0.95, 0.85);
    }
    return sky;
  }
  std::string name() const override { return name_; }

 private:
  static constexpr double kSunRadiusRad = 1.5 * kPi / 180.0;
  static constexpr double kSunLimbRad = 0.15 * kPi / 180.0;
  glm::dvec3 sun_dir_;
  std::string name_;
  double sun_radiance_ = 0.0;
  // A hair wider than the disc and its limb, so rounding never drops an edge direction.
  double cos_outer_edge_ = std::cos((kSunRadiusRad + kSunLimbRad) * 1.001);
};

// The difference of two azimuths in degrees, wrapped to [-180, 180].
double azimuthDifferenceDeg(double a_deg, double b_deg) {
  double d = a_deg - b_deg;
  // Azimuths from atan2 and the boxes' own differ by less than 540 deg: one
  // step of 360 wraps them, where std::remainder is a slow library call.
  if (std::abs(d) > 540.0) return std::remainder(d, 360.0);
  if (d > 180.0) return d - 360.0;
  if (d < -180.0) return d + 360.0;
  return d;
}

// A rectangle in (azimuth, elevation), with softened edges.
struct AngularBox {
  double azimuth_deg, elevation_deg, width_deg, height_deg;
  glm::dvec3 radiance;

  double elevationWeight(double elevation_deg_query) const {
    return smoothEdge(height_deg / 2 - std::abs(elevation_deg_query - elevation_deg), 1.0);
  }
  double azimuthWeight(double azimuth_deg_query) const {
    return smoothEdge(width_deg / 2 - std::abs(azimuthDifferenceDeg(azimuth_deg_query, azimuth_deg)), 1.0);
  }
};

double elevationDeg(const glm::dvec3& dir) { return std::asin(std::clamp(dir.z, -1.0, 1.0)) * 180.0 / kPi; }
double azimuthDeg(const glm::dvec3& dir) { return std::atan2(dir.y, dir.x) * 180.0 / kPi; }

// The sum of the boxes' radiance seen along dir. The azimuth (atan2) is
// computed only when dir is within some box's band of elevations.
template <std::size_t N>
glm::dvec3 boxRadiance(const AngularBox (&boxes)[N], const glm::dvec3& dir, double& weight_of_first) {
  glm::dvec3 result(0.0);
  const double elevation = elevationDeg(dir);
  double azimuth = 0.0;
  bool have_azimuth = false;
  weight_of_first = 0.0;
  for (std::size_t i = 0; i < N; ++i) {
    const double elevation_weight = boxes[i].elevationWeight(elevation);
    if (elevation_weight == 0.0) continue;
    if (!have_azimuth) azimuth = azimuthDeg(dir), have_azimuth = true;
    const double weight = boxes[i].azimuthWeight(azimuth) * elevation_weight;
    if (i == 0) weight_of_first = weight;
    result += weight * boxes[i].radiance;
  }
  return result;
}

// A street at night: a dark sky over darker facades, lit by two small
// lamps low over the street: the lights a ball easily has behind it.
class NightStreetEnvironment : public Environment {
 public:
  NightStreetEnvironment() {
    const double disc = 2.0 * kPi * (1.0 - std::cos(kLampRadiusRad));
    // Each lamp's irradiance at normal incidence: 30x the sky's E_up (pi * 0.01).
    lamp_radiance_ = 30.0 * kPi * 0.01 / disc;
    lamps_[0] = directionFromAzimuthElevation(degToRad(60.0), degToRad(8.0));
    lamps_[1] = directionFromAzimuthElevation(degToRad(180.0), degToRad(15.0));
  }
  glm::dvec3 radiance(const glm::dvec3& dir) const override {
    // Facades up to 25 deg, the sky above.
    glm::dvec3 value = dir.z < std::sin(degToRad(25.0)) ? glm::dvec3(0.03, 0.028, 0.025) : glm::dvec3(0.008, 0.01, 0.014);
    for (const glm::dvec3& lamp : lamps_) {
      const double cos_angle = std::clamp(glm::dot(dir, lamp), -1.0, 1.0);
      if (cos_angle < std::cos(kLampRadiusRad + kLampLimbRad)) continue;
      value += smoothEdge(kLampRadiusRad - std::acos(cos_angle), 2.0 * kLampLimbRad) * lamp_radiance_ *
               glm::dvec3(1.0, 0.8, 0.55);  // sodium-ish
    }
    return value;
  }
  std::string name() const override { return "night_street"; }

 private:
  static constexpr double kLampRadiusRad = 2.0 * kPi / 180.0;
  static constexpr double kLampLimbRad = 0.2 * kPi / 180.0;
  glm::dvec3 lamps_[2];
  double lamp_radiance_ = 0.0;
};

class StudioEnvironment : public Environment {
 public:
  glm::dvec3 radiance(const glm::dvec3& dir) const override {
    double unused;
    return glm::dvec3(0.02) + boxRadiance(kBoxes, dir, unused);
  }
  std::string name() const override { return "studio"; }

 private:
  static inline const AngularBox kBoxes[3] = {
      {-60.0, 35.0, 40.0, 30.0, {12.0, 11.5, 10.5}},  // key, warm
      {150.0, 20.0, 30.0, 40.0, {3.5, 4.0, 4.5}},     // fill, cool
      {0.0, 75.0, 60.0, 20.0, {6.0, 6.0, 6.0}},       // top
  };
};

class OvercastEnvironment : public Environment {
 public:
  glm::dvec3 radiance(const glm::dvec3& dir) const override {
    double cos_theta = std::max(0.0, dir.z);
    return glm::dvec3((1.0 + 2.0 * cos_theta) / 3.0);
  }
  std::string name() const override { return "overcast"; }
};

class ColouredWallEnvironment : public Environment {
 public:
  glm::dvec3 radiance(const glm::dvec3& dir) const override {
    glm::dvec3 sky(0.6 + 0.4 * std::max(0.0, dir.z));
    double wall = 0.0;
    boxRadiance(kWalls, dir, wall);
    return (1.0 - wall) * sky + wall * kWalls[0].radiance;
  }
  std::string name() const override { return "coloured_wall"; }

 private:
  // A wall from the horizon up to 50 deg, 120 deg wide, centred on +X.
  static inline const AngularBox kWalls[1] = {{0.0, 25.0, 120.0, 50.0, {2.4, 0.35, 0.12}}};
};

}  // namespace

glm::dvec2 latLongUvFromDirection(const glm::dvec3& dir) {
  double theta = std::acos(std::clamp(dir.z, -1.0, 1.0));
  double phi = std::atan2(dir.y, dir.x);
  double u = 0.5 - phi / (2.0 * kPi);
  u -= std::floor(u);
  return {u, theta / kPi};
}

glm::dvec3 directionFromLatLongUv(const glm::dvec2& uv) {
  double theta = uv.y * kPi;
  double phi = 2.0 * kPi * (0.5 - uv.x);
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

LatLongEnvironment::LatLongEnvironment(cv::Mat rgb, std::string name) : rgb_(std::move(rgb)), name_(std::move(name)) {}

std::unique_ptr<LatLongEnvironment> LatLongEnvironment::load(const std::string& path) {
  // OpenCV refuses EXR unless asked (CVE hardening); 0 keeps a user's choice.
  setenv("OPENCV_IO_ENABLE_OPENEXR", "1", 0);
  if (!std::filesystem::exists(path)) throw SceneError("environment file '" + path + "' does not exist");
  cv::Mat image;
  try {
    image = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    // OpenCV throws when a header claims more pixels than it allows.
    image = cv::Mat();
  }
  if (image.empty())
    throw SceneError("environment file '" + path + "' could not be decoded as an .hdr/.exr image");
  if (image.channels() < 3)
    throw SceneError("environment file '" + path + "' has " + std::to_string(image.channels()) +
                     " channel(s); need RGB");
  if (std::abs(image.cols - 2 * image.rows) > image.rows / 50 || image.rows < 2)
    throw SceneError("environment file '" + path + "' is " + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + ", not a 2:1 lat-long panorama");
  cv::Mat as_float;
  image.convertTo(as_float, CV_32F);
  cv::Mat rgb;
  cv::cvtColor(as_float, rgb, image.channels() == 4 ? cv::COLOR_BGRA2RGB : cv::COLOR_BGR2RGB);
  // Negative or NaN texels (seen in some EXRs) would poison every integral.
  rgb.forEach<cv::Vec3f>([](cv::Vec3f& p, const int*) {
    for (int c = 0; c < 3; ++c)
      if (!(p[c] >= 0.0f) || !std::isfinite(p[c])) p[c] = 0.0f;
  });
  return std::make_unique<LatLongEnvironment>(rgb, path);
}

glm::dvec3 LatLongEnvironment::radiance(const glm::dvec3& dir) const {
  glm::dvec2 uv = latLongUvFromDirection(dir);
  const int width = rgb_.cols, height = rgb_.rows;
  double x = uv.x * width - 0.5;
  double y = std::clamp(uv.y * height - 0.5, 0.0, height - 1.0);
  int x0 = static_cast<int>(std::floor(x));
  int y0 = std::min(static_cast<int>(y), height - 2);  // load() guarantees height >= 2
  double fx = x - x0, fy = y - y0;
  int y1 = std::min(y0 + 1, height - 1);
  x0 = ((x0 % width) + width) % width;
  int x1 = (x0 + 1) % width;
  auto at = [&](int yy, int xx) {
    const cv::Vec3f& p = rgb_.at<cv::Vec3f>(yy, xx);
    return glm::dvec3(p[0], p[1], p[2]);
  };
  return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x1)) + fy * ((1 - fx) * at(y1, x0) + fx * at(y1, x1));
}

std::unique_ptr<Environment> makeEnvironment(const std::string& name_or_path) {
  if (name_or_path == "uniform") return std::make_unique<UniformEnvironment>();
  if (name_or_path == "sun_sky") return std::make_unique<SunSkyEnvironment>();
  if (name_or_path == "sunrise") return std::make_unique<SunSkyEnvironment>(4.0, "sunrise");
  if (name_or_path == "night_street") return std::make_unique<NightStreetEnvironment>();
  if (name_or_path == "studio") return std::make_unique<StudioEnvironment>();
  if (name_or_path == "overcast") return std::make_unique<OvercastEnvironment>();
  if (name_or_path == "coloured_wall") return std::make_unique<ColouredWallEnvironment>();
  std::string extension = std::filesystem::path(name_or_path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
  if (extension == ".hdr" || extension == ".exr") return LatLongEnvironment::load(name_or_path);
  std::string known;
  for (const std::string& name : environmentNames()) known += (known.empty() ? "" : ", ") + name;
  throw SceneError("environment '" + name_or_path + "' is neither a known name (" + known +
                   ") nor an .hdr/.exr file");
}

}  // namespace probelight::sim
