// Scripted camera motion: a pose for every frame index, deterministic.
#pragma once

#include <cstdint>
#include <memory>

#include "core/types.hpp"
#include "sim/scene_config.hpp"

namespace probelight::sim {

// Camera at eye_w looking at target_w with the image's "up" (-y_cam) as close
// to +Z as possible, then rolled by roll_rad about the viewing axis. Looking
// straight down, image up falls back to +Y.
PoseCamFromWorld lookAtPose(const glm::dvec3& eye_w, const glm::dvec3& target_w, double roll_rad = 0.0);

// Eye position from spherical coordinates around target (degrees).
glm::dvec3 orbitEye(const glm::dvec3& target_w, double distance_m, double elevation_deg, double azimuth_deg);

// Seeded random views that keep the whole tag (unoccluded) and the whole ball
// in the image with a margin. A third are grazing (elevation 20-25 deg), a
// third nearly fronto-parallel (78-88 deg, looking almost straight down), the
// rest in between.
class RandomPoseGenerator {
 public:
  RandomPoseGenerator(const CameraIntrinsics& camera, const RigGeometry& rig, double post_radius_m,
                      double min_distance_m = 0.45, double max_distance_m = 0.75, double margin_px = 10.0);
  // Same (seed, index) -> same pose. Throws SceneError if no view fits after
  // many tries (a rig too big for the camera).
  PoseCamFromWorld pose(std::uint64_t seed, std::uint64_t index) const;

 private:
  CameraIntrinsics camera_;
  RigGeometry rig_;
  double post_radius_m_;
  double min_distance_m_, max_distance_m_, margin_px_;
};

class CameraPath {
 public:
  virtual ~CameraPath() = default;
  PoseCamFromWorld pose(std::uint64_t frame_index) const { return poseAt(static_cast<double>(frame_index)); }
  // The pose at a time between frames (in frame intervals), for a shutter
  // open across it (motion blur). The smooth paths move continuously; the
  // random path's independent views hold for the half-frame either side
  // of their own.
  virtual PoseCamFromWorld poseAt(double frame_time) const = 0;
};

// Throws SceneError naming camera_path.name when unknown.
std::unique_ptr<CameraPath> makeCameraPath(const SceneConfig& scene);

// Default look-at point: halfway between the tag centre and the ball centre.
glm::dvec3 defaultLookAt(const RigGeometry& rig);

}  // namespace probelight::sim
