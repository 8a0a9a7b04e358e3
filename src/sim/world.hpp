// The simulated world: the oracle the pipeline is checked against. It renders
// camera frames of a tag on a floor with a mirror ball on a post, and answers
// what the truth is (pose, ball outline, light arriving at the ball) by its own
// ray tracing and brute-force integration. It never uses src/ibl.
//
// Modelling choices a caller should know:
// - Ground (floor and tag) is Lambertian, lit by the environment's upper
//   hemisphere only: radiance = albedo * E_up / pi. Shadows and light bounced
//   by the ball and post are ignored.
// - The ball is a perfect mirror times rig.probe_reflectance (no Fresnel). Its
//   reflected rays see the ground when heading down, else the environment; they
//   do not see the post, the ball itself or the camera.
// - The post is Lambertian; its irradiance comes from the sky plus a uniform
//   floor below.
// - "Camera linear units": value = scene radiance * exposure(), before the
//   clip at 1 and the sRGB encoding.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "sim/scene_config.hpp"

namespace probelight::sim {

enum class SceneObject : std::uint8_t { kEnvironment = 0, kFloor = 1, kTag = 2, kProbe = 3, kPost = 4 };

// In camera linear units. hdr: what an ideal sensor would integrate. clipped:
// the same integral of min(L * exposure * reflectance, 1) / reflectance, i.e.
// what can be known through the ball from an 8-bit camera that clips.
struct IrradianceTruth {
  glm::dvec3 hdr{0.0};
  glm::dvec3 clipped{0.0};
};
struct RadianceTruth {
  glm::dvec3 hdr{0.0};
  glm::dvec3 clipped{0.0};
};

struct LightingState {
  double environment_rotation_rad = 0.0;  // config rotation + sun azimuth script
  bool lamp_on = false;
};

class World {
 public:
  // Loads the environment and precomputes camera rays. Throws SceneError with
  // a one-line message naming the bad field or file.
  explicit World(SceneConfig scene);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const SceneConfig& scene() const;

  // Renders frame `frame_index` (8-bit sRGB, noise included) and its truth.
  // Thread-safe and deterministic: the same index gives the same bytes.
  void render(std::uint64_t frame_index, ImageRGB8& out, FrameTruth& truth) const;
  FrameTruth truth(std::uint64_t frame_index) const;
  PoseCamFromWorld pose(std::uint64_t frame_index) const;
  double exposure() const;
  LightingState lighting(std::uint64_t frame_index) const;

  // Light arriving at the ball centre from all directions on a surface with
  // normal normal_w (unit). The lower hemisphere is the ground as seen from the
  // ball centre (floor texture and tag included). Brute force over a 512x256
  // lat-long grid (3x3 sub-samples a cell) with exact solid-angle cosine
  // moments; cached per lighting state (the first query of a state takes tens
  // of milliseconds).
  IrradianceTruth irradiance(const glm::dvec3& normal_w, std::uint64_t frame_index) const;
  // Radiance the ball centre sees along dir_w (unit): what the reflection cube
  // map should show, divided by nothing (the reflectance is already undone).
  RadianceTruth radiance(const glm::dvec3& dir_w, std::uint64_t frame_index) const;
  // Upward-normal environment irradiance that lights the ground, scene units.
  glm::dvec3 groundIrradianceUp(std::uint64_t frame_index) const;

  // Per pixel (row-major), the fraction of the pixel's sub-samples whose
  // camera ray first hits `object`. Same rays as render().
  std::vector<float> coverage(std::uint64_t frame_index, SceneObject object) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace probelight::sim
