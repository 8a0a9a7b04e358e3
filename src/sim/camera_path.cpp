#include "sim/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/math_constants.hpp"
#include "sim/scene_geometry.hpp"

namespace probelight::sim {
namespace {

std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + index + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

class StaticPath : public CameraPath {
 public:
  explicit StaticPath(PoseCamFromWorld pose) : pose_(pose) {}
  PoseCamFromWorld poseAt(double) const override { return pose_; }

 private:
  PoseCamFromWorld pose_;
};

class OrbitPath : public CameraPath {
 public:
  OrbitPath(glm::dvec3 target, const CameraPathConfig& config) : target_(target), config_(config) {}
  PoseCamFromWorld poseAt(double frame) const override {
    double azimuth = config_.azimuth_start_deg + config_.azimuth_rate_deg_per_frame * frame;
    return lookAtPose(orbitEye(target_, config_.distance_m, config_.elevation_deg, azimuth), target_);
  }

 private:
  glm::dvec3 target_;
  CameraPathConfig config_;
};

// Sums of incommensurate slow sinusoids (0.1-0.6 Hz at 30 fps): smooth,
// never periodic within a test, like a hand that tries to hold still.
class SlowWobblePath : public CameraPath {
 public:
  SlowWobblePath(glm::dvec3 target, const CameraPathConfig& config) : target_(target), config_(config) {}
  PoseCamFromWorld poseAt(double frame) const override {
    const double t = frame / 30.0;
    auto wobble = [t](double f1, double f2, double phase) {
      return 0.6 * std::sin(2 * kPi * f1 * t + phase) + 0.4 * std::sin(2 * kPi * f2 * t + 2.1 * phase);
    };
    const double a = config_.wobble_angle_deg;
    double azimuth = config_.azimuth_start_deg + a * wobble(0.13, 0.41, 0.3);
    double elevation = config_.elevation_deg + a * wobble(0.17, 0.53, 1.1);
    double distance = config_.distance_m + config_.wobble_distance_m * wobble(0.11, 0.37, 2.3);
    glm::dvec3 target = target_ + 0.004 * glm::dvec3(wobble(0.19, 0.59, 0.7), wobble(0.23, 0.47, 1.7), 0.0);
    double roll = degToRad(a * 0.5 * wobble(0.29, 0.61, 2.9));
    return lookAtPose(orbitEye(target, distance, elevation, azimuth), target, roll);
  }

 private:
  glm::dvec3 target_;
  CameraPathConfig config_;
};

// A hand-held sweep: the kiosk carried in an arc around the rig and back
// (sweep_azimuth_deg either side of the start, rising and falling by
// sweep_elevation_deg, one way in sweep_seconds at 30 fps, eased at the
// turns like an arm), with the slow wobble of a hand on top.
class HandHeldSweepPath : public CameraPath {
 public:
  HandHeldSweepPath(glm::dvec3 target, const CameraPathConfig& config) : target_(target), config_(config), wobble_(target, config) {}
  PoseCamFromWorld poseAt(double frame) const override {
    const double one_way_frames = std::max(1.0, 30.0 * config_.sweep_seconds);
    // 0 -> 1 -> 0 over two sweeps, with the arm's ease (a cosine) at each end.
    const double phase = std::fmod(std::max(frame, 0.0) / one_way_frames, 2.0);
    const double along = 0.5 - 0.5 * std::cos(kPi * phase);
    const double azimuth = config_.azimuth_start_deg + config_.sweep_azimuth_deg * (2.0 * along - 1.0);
    const double elevation = config_.elevation_deg + config_.sweep_elevation_deg * std::sin(kPi * along);
    // The hand's drift: the wobble path's offsets from its own start.
    const PoseCamFromWorld drift = wobble_.poseAt(frame);
    const glm::dvec3 drift_eye = drift.cameraCenterWorld() -
                                 orbitEye(target_, config_.distance_m, config_.elevation_deg, config_.azimuth_start_deg);
    return lookAtPose(orbitEye(target_, config_.distance_m, elevation, azimuth) + drift_eye, target_);
  }

 private:
  glm::dvec3 target_;
  CameraPathConfig config_;
  SlowWobblePath wobble_;
};

// A pan: the static pose turned about the camera's own vertical (its y
// axis, the image's columns) through its centre by amplitude
// sin(2 pi t / period): the image sweeps along its rows.
class PanPath : public CameraPath {
 public:
  PanPath(glm::dvec3 target, const CameraPathConfig& config)
      : config_(config),
        still_(lookAtPose(orbitEye(target, config.distance_m, config.elevation_deg, config.azimuth_start_deg), target)) {}
  PoseCamFromWorld poseAt(double frame) const override {
    const double t = frame / 30.0;
    const double yaw = degToRad(config_.pan_amplitude_deg) * std::sin(2 * kPi * t / config_.pan_period_s);
    // x_cam = Ry(yaw) (x_still_cam): the camera turned by -yaw about its y axis.
    const double c = std::cos(yaw), s = std::sin(yaw);
    const glm::dmat3 turn(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);  // Ry(yaw), columns
    const glm::dvec3 eye = still_.cameraCenterWorld();
    PoseCamFromWorld pose;
    pose.R_cam_from_world = turn * still_.R_cam_from_world;
    pose.t_cam_from_world = -(pose.R_cam_from_world * eye);
    return pose;
  }

 private:
  CameraPathConfig config_;
  PoseCamFromWorld still_;
};

class RandomPath : public CameraPath {
 public:
  RandomPath(const SceneConfig& scene)
      : generator_(scene.camera, scene.rig, scene.post_radius_m, scene.camera_path.random_min_distance_m,
                   scene.camera_path.random_max_distance_m),
        seed_(scene.seed) {}
  PoseCamFromWorld poseAt(double frame) const override {
    return generator_.pose(seed_, static_cast<std::uint64_t>(std::llround(std::max(frame, 0.0))));
  }

 private:
  RandomPoseGenerator generator_;
  std::uint64_t seed_;
};

}  // namespace

PoseCamFromWorld lookAtPose(const glm::dvec3& eye_w, const glm::dvec3& target_w, double roll_rad) {
  glm::dvec3 forward = glm::normalize(target_w - eye_w);
  glm::dvec3 up{0.0, 0.0, 1.0};
  if (std::abs(glm::dot(forward, up)) > 0.999) up = {0.0, 1.0, 0.0};
  glm::dvec3 right = glm::normalize(glm::cross(forward, up));
  glm::dvec3 down = glm::cross(forward, right);
  const double c = std::cos(roll_rad), s = std::sin(roll_rad);
  glm::dvec3 rolled_right = c * right + s * down;
  glm::dvec3 rolled_down = -s * right + c * down;
  PoseCamFromWorld pose;
  // Rows of R are the camera axes in W; glm stores columns, so transpose.
  pose.R_cam_from_world = glm::transpose(glm::dmat3(rolled_right, rolled_down, forward));
  pose.t_cam_from_world = -(pose.R_cam_from_world * eye_w);
  return pose;
}

glm::dvec3 orbitEye(const glm::dvec3& target_w, double distance_m, double elevation_deg, double azimuth_deg) {
  double el = degToRad(elevation_deg), az = degToRad(azimuth_deg);
  return target_w + distance_m * glm::dvec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
}

glm::dvec3 defaultLookAt(const RigGeometry& rig) { return 0.5 * rig.probe_center_w; }

RandomPoseGenerator::RandomPoseGenerator(const CameraIntrinsics& camera, const RigGeometry& rig, double post_radius_m,
                                         double min_distance_m, double max_distance_m, double margin_px)
    : camera_(camera),
      rig_(rig),
      post_radius_m_(post_radius_m),
      min_distance_m_(min_distance_m),
      max_distance_m_(max_distance_m),
      margin_px_(margin_px) {}

PoseCamFromWorld RandomPoseGenerator::pose(std::uint64_t seed, std::uint64_t index) const {
  std::mt19937_64 rng(mixSeed(seed, index));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const glm::dvec3 centre = defaultLookAt(rig_);
  // The kind is fixed per index so a run of indices covers all three evenly.
  const int kind = static_cast<int>(index % 3);
  for (int attempt = 0; attempt < 2000; ++attempt) {
    double elevation = kind == 0 ? 20.0 + 5.0 * unit(rng) : kind == 1 ? 78.0 + 10.0 * unit(rng) : 25.0 + 53.0 * unit(rng);
    double azimuth = 360.0 * unit(rng);
    double distance = min_distance_m_ + (max_distance_m_ - min_distance_m_) * unit(rng);
    glm::dvec3 target = centre + 0.03 * glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, 0.0);
    double roll = degToRad(30.0 * (unit(rng) - 0.5));
    PoseCamFromWorld candidate = lookAtPose(orbitEye(target, distance, elevation, azimuth), target, roll);
    if (!tagFullyVisible(camera_, rig_, post_radius_m_, candidate, margin_px_)) continue;
    ProbeOutline outline = probeOutline(camera_, candidate, rig_.probe_center_w, rig_.probe_radius_m, 90);
    if (!outline.valid) continue;
    bool ball_inside = true;
    for (const glm::dvec2& p : outline.polygon_px) ball_inside = ball_inside && pointInImage(camera_, p, margin_px_);
    if (ball_inside) return candidate;
  }
  throw SceneError("random camera pose: no view keeps tag and ball in the image (camera too narrow for the rig?)");
}

std::unique_ptr<CameraPath> makeCameraPath(const SceneConfig& scene) {
  const CameraPathConfig& config = scene.camera_path;
  const glm::dvec3 target = config.look_at_w.value_or(defaultLookAt(scene.rig));
  if (!(config.distance_m > 0.0)) throw SceneError("camera_path.distance_m must be positive");
  if (config.name == "static")
    return std::make_unique<StaticPath>(
        lookAtPose(orbitEye(target, config.distance_m, config.elevation_deg, config.azimuth_start_deg), target));
  if (config.name == "orbit") return std::make_unique<OrbitPath>(target, config);
  if (config.name == "slow_wobble") return std::make_unique<SlowWobblePath>(target, config);
  if (config.name == "hand_held_sweep") return std::make_unique<HandHeldSweepPath>(target, config);
  if (config.name == "random") return std::make_unique<RandomPath>(scene);
  if (config.name == "pan") {
    if (!(config.pan_period_s > 0.0)) throw SceneError("camera_path.pan_period_s must be positive");
    return std::make_unique<PanPath>(target, config);
  }
  std::string known;
  for (const std::string& name : cameraPathNames()) known += (known.empty() ? "" : ", ") + name;
  throw SceneError("camera_path.name '" + config.name + "' is unknown (choose " + known + ")");
}

}  // namespace probelight::sim
