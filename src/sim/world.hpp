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
#include "sim/occluder.hpp"
#include "sim/scene_config.hpp"

namespace probelight::sim {

// kOccluder: a VirtualOccluder, only in World::renderWithOccluders frames.
enum class SceneObject : std::uint8_t { kEnvironment = 0, kFloor = 1, kTag = 2, kProbe = 3, kPost = 4, kOccluder = 5 };

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
  // `exposure_ev` shortens (< 0) or lengthens the exposure by that many
  // stops, as a bracket frame; the truth stays in the scene exposure's
  // camera linear units. `channel_gain` multiplies the linear light per
  // channel before the noise and the clip: a white balance's gains.
  // `shutter_frames`: the shutter is open this many frame intervals,
  // centred on the frame's time (the truth's pose is the middle of the
  // exposure), and the camera's linear light is averaged over its poses
  // along the camera path across it: motion blur (0: an instant).
  void render(std::uint64_t frame_index, ImageRGB8& out, FrameTruth& truth, double exposure_ev = 0.0,
              const glm::dvec3& channel_gain = glm::dvec3(1.0), double shutter_frames = 0.0) const;
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
  // The irradiance the post is lit with where its (horizontal) normal is
  // normal_w, in camera linear units: what a reading of the post should
  // find (0 when post_albedo is 0).
  glm::dvec3 postIrradiance(const glm::dvec3& normal_w, std::uint64_t frame_index) const;
  // Upward-normal environment irradiance that lights the ground, scene units.
  glm::dvec3 groundIrradianceUp(std::uint64_t frame_index) const;

  // Per pixel (row-major), the fraction of the pixel's sub-samples whose
  // camera ray first hits `object`. Same rays as render().
  std::vector<float> coverage(std::uint64_t frame_index, SceneObject object) const;

  // Fraction of the ground's irradiance that still arrives at each ground point
  // (x, y, 0) when the occluders stand in the scene: 1 = unshadowed, per RGB channel.
  // The ground's irradiance is the same upper-hemisphere integral that lights the
  // simulated floor (environment + lamp, World::groundIrradianceUp), so
  // fraction = 1 - (integral over directions blocked by an occluder of L cos) / E_up.
  // hdr: with the true radiance; clipped: with what an 8-bit camera can know
  // through the ball (the same per-cell clipped radiance as World::irradiance's
  // `clipped`, i.e. min(L * exposure * reflectance, 1) / reflectance).
  // Brute force over the simulator's 512x256 direction grid with exact cosine moments,
  // testing each cell's visibility against the occluders.
  // Cells cut by an occluder's outline are split 3x3 (as the irradiance's
  // sub-samples), and pieces still cut and carrying more than 1e-5 of E_up
  // (the sun, a lamp) 3x3 again, down to 1/81 of a cell (0.009 deg), so a
  // sun's shadow edge is smooth. Thread-safe; uses scene().render_threads.
  struct GroundShadowTruth { glm::dvec3 hdr{1.0}; glm::dvec3 clipped{1.0}; };
  std::vector<GroundShadowTruth> groundShadow(const std::vector<glm::dvec2>& ground_points_w,
                                              const std::vector<VirtualOccluder>& occluders,
                                              std::uint64_t frame_index) const;
  // The frame as if the occluders were real objects: render() plus the occluders
  // (Lambertian, albedo, lit by the brute-force irradiance at their surface normal
  // over the whole sphere of directions as World::irradiance computes it for the
  // ball centre -- a stated approximation: the occluder is lit as if it stood at
  // the ball, with no shadow from itself, another occluder or the rig) and the
  // ground darkened by groundShadow's hdr fraction at each ground pixel's hit
  // point. Same sensor model, noise and determinism as render(). Occluders hide
  // what is behind them (tag, floor, ball, post); the ball's reflection and the
  // post's lighting ignore them. Further approximations, each far below one
  // code value or confined to a pixel: the shadow is interpolated bilinearly
  // from a ground grid of exact values (2 mm within 10 cm of an occluder, its
  // spacing at most 4% of the distance further out, where shadows are wider
  // in proportion), a shadow deficit under kIgnoredShadowDeficit is
  // dropped (so ground far from the occluders renders byte for byte as in
  // render()), and the occluders' irradiance is interpolated from a 64x32
  // table of normals. truth.tag_fully_visible / probe_fully_visible also turn
  // false when an occluder hides part of the tag / of the ball's outline.
  // A kMesh occluder (a user's model, meshOccluder) is shaded otherwise: by
  // path tracing its own glTF materials (sim/gltf_brdf) against the sky
  // (drawn by its brightness, multiple importance sampling with the BRDF),
  // its own triangles (self-occlusion, and interreflection up to its
  // max_bounces) and the shadowed floor below, path_samples paths per
  // shaded sample; see shadeMesh in world.cpp for what it leaves out.
  //
  // `window`: only the pixels in it are rendered, the rest left black (0);
  // each rendered pixel is the same as in the whole frame. With
  // occluders_only, what the occluders do not cover is black too (an edge
  // pixel holds only the occluder's share of its light): a model's truth
  // without the exact ground shadow of the floor around it, whose grid of
  // exact nodes (thousands of rays each near a mesh) is most of a truth
  // frame's cost.
  struct PixelWindow {
    int x_begin = 0, y_begin = 0, x_end = 0, y_end = 0;  // [begin, end) in pixels
    bool occluders_only = false;
  };
  // A lamp standing in the scene (issue 19's virtual light, rendered as if
  // it were real): a point light, or a spot of smooth edge, lighting the
  // ground (floor and tag) only. Its irradiance on the ground at p is
  //   intensity x colour x Y(E_up) x cos(theta) / d^2 x spot(p)
  // (E_up: groundIrradianceUp, Y its Rec. 709 luminance), added to the
  // ground's light where nothing stands between p and the lamp: the
  // occluders, the ball and its post. spot(p) is smoothstep from the cosine
  // of (half-angle + softness / 2) to that of (half-angle - softness / 2)
  // off its axis; a half-angle of 180 is a point light.
  struct Lamp {
    glm::dvec3 position_w{0.0, 0.0, 0.3};
    glm::dvec3 colour{1.0};
    double intensity = 0.0;
    glm::dvec3 spot_direction_w{0.0, 0.0, -1.0};
    double spot_half_angle_deg = 180.0;
    double spot_softness_deg = 5.0;
  };
  void renderWithOccluders(std::uint64_t frame_index, const std::vector<VirtualOccluder>& occluders,
                           ImageRGB8& out, FrameTruth& truth, const PixelWindow* window = nullptr,
                           const Lamp* lamp = nullptr) const;
  // Below this (every channel) renderWithOccluders leaves the ground unshadowed:
  // it changes an 8-bit sRGB code by at most 0.44 * 255 * deficit = 0.02.
  static constexpr double kIgnoredShadowDeficit = 2e-4;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace probelight::sim
