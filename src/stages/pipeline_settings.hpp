// The settings of the per-frame pipeline's stages: the sections of
// probelight.yaml that `run`, `analyze` and `render` all read, so that each
// means the same in every command. AppSettings (app/app_settings.hpp) adds
// what only the kiosk's wiring reads (button, screen, simulator, output).
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "ibl/virtual_lamp.hpp"
#include "ibl/light_dome.hpp"
#include "passes/environment_maps.hpp"
#include "stages/lighting_state_machine.hpp"
#include "stages/map_update_policy.hpp"
#include "tracking/pose_smoother.hpp"

namespace probelight {

enum class DiffuseMethod {
  kCosinePasses,  // two separable cosine passes on the GPU (ibl::irradianceOverPiByCosinePasses)
  kSH9,           // Ramamoorthi & Hanrahan's 9 coefficients, projected on the CPU
};

struct EnvironmentMapConfig {
  // Sizes, taps and iterations, with the pipeline's own defaults.
  passes::EnvironmentMapSettings stages;
  DiffuseMethod diffuse_method = DiffuseMethod::kCosinePasses;
  bool force_8bit = false;  // ignore float render-target extensions (tests the GLES2 fallback)
  // Each view merged into a probe over views (stages/probe_merge.hpp): what
  // one view hides behind its ball comes from the others, and from the
  // frame around the ball. false: each map update is its view alone.
  bool merge_views = true;
};

struct TrackingConfig {
  double quad_decimate = 2.0;
  int threads = 1;  // libapriltag's worker threads, at most tracking::maxDetectorThreads()
  double quad_sigma = 0.0;
  bool refine_edges = true;
  bool refine_corners = true;  // full-resolution linear-light edge fit (tracking/corner_refiner.hpp)
  double refinement_reuse_px = 0.1;  // a still tag keeps its refinement (tracking/refinement_reuse.hpp)
  int refinement_reuse_frames = 30;
  bool track_in_window = true;     // search a window around the predicted tag (tracking/tag_detector.hpp)
  int full_frame_every_frames = 30;
  tracking::PoseSmoothingSettings smoothing;  // tracking/pose_smoother.hpp
};

// Refining the rig's ball position and radius from the image, over frames
// (tracking/probe_edge_fit.hpp). Off by default: a fit is good to a few
// tenths of a pixel per view, so it helps a rig measured millimetres wrong and
// costs a correct one a little.
struct ProbeRefinementConfig {
  bool enabled = false;
  double weight = 0.1;  // each frame's fit moves the correction this far toward it (30 frames: 96% of the way)
};

// The dome of shadow-casting lights (ibl/light_dome.hpp) and the ground
// shadow (passes/ground_shadow.hpp).
struct LightsConfig {
  ibl::LightDomeSettings dome;  // count 8, clustered placement
  double fade_s = 0.5;          // new lights move and fade in over this long
  bool shadows = true;
  // Shadow maps are remade only when the lights change (fading after a fit);
  // true remakes them every frame: the worst case, for benchmarks.
  bool shadows_every_frame = false;
  int shadow_map_size_px = 256;
  int ground_texture_size_px = 256;
  double max_shadow_reach_m = 0.5;  // from the object, for lights near the horizon
  // Refit the lights when the ground's irradiance in the diffuse map moves by
  // more than refit_change_fraction since the last fit (a lamp switched on).
  // 10%: the map of a still scene moves by well under 1% from noise (the
  // update policy's blend halves it again), and a light that changes the
  // ground's light by less makes shadows that differ by less than that.
  bool refit_when_light_changes = false;
  double refit_change_fraction = 0.1;
  // At each fit, the tag's white border (rig.yaml tag_white_albedo) gives
  // the ball's clipped highlights the light they hide
  // (ibl/white_reference.hpp): the dome is fitted from the corrected map and
  // the object shaded with the clipped lights until the next fit.
  bool white_reference = true;
  // ... and the ball's post, where rig.yaml describes one (post_radius,
  // post_albedo), divides that light between the clipped regions by its
  // readings at the normals it turns to the camera (ibl/post_reference.hpp).
  bool post_reference = true;
  // At each fit whose frame shows the ball clipped, `run` takes shorter
  // exposures, bracket_step_stops apart, while the ball still clips, down
  // to bracket_max_stops under the frame's (0: no bracket), and fits the
  // lights from them merged (the white border is then not needed). 3 stops
  // keep two frames' well-exposed ranges overlapping (8-bit sRGB codes
  // 6..250 span about 11 stops); 12 stops reach a sun from a sky.
  double bracket_step_stops = 3.0;
  double bracket_max_stops = 12.0;
};

struct ObjectConfig {
  double radius_m = 0.035;             // a sphere resting on the ground
  glm::dvec2 position_w{0.0, 0.0};     // where it rests, in W (metres)
  glm::dvec3 albedo{0.8, 0.8, 0.8};
  double k_specular = 0.25;
  double shininess = 48.0;
  double k_reflect = 0.08;
  // 1: the reflection term is a mirror; 0: it reads the diffuse map; between,
  // it blends the glossy levels (src/ibl/surface_shading.hpp).
  double glossiness = 1.0;
  // A glTF 2.0 model (.gltf or .glb) instead of the sphere, with its own
  // materials: standing at position_w, turned by yaw_deg about +Z and
  // scaled, its lowest point on the ground (model/model_placement.hpp).
  // Relative paths are the config file's directory's.
  std::string model_path;
  double yaw_deg = 0.0;
  double scale = 1.0;
  // A model's shadow on itself from the dome's lights (the ground shadow's
  // maps of its near side, read by its shader). Off saves the near-side
  // maps and most of the model's fragment work (8 map reads a pixel), and
  // shows a concave model's hollows as bright as its open faces.
  bool self_shadow = true;
};

// The board's camera (--source libcamera); its size is camera.yaml's.
struct CameraConfig {
  std::string id;  // libcamera's camera id; empty: the first camera
  // "auto": the first the camera offers of YUV420, NV12, YUYV, BGR888,
  // RGB888, XRGB8888, MJPEG (capture/camera_format_choice.hpp), or one of
  // those by name (lower case); a camera that does not offer it is refused
  // with the formats it does offer.
  std::string pixel_format = "auto";
  // Freeze auto exposure and white balance while the lights are fitted, so
  // that every frame of a recalibration sees the ball alike. Not during the
  // first `exposure_settle_frames` after the camera starts (AE is still
  // converging: locking then would keep a wrong exposure).
  bool lock_exposure = true;
  int exposure_settle_frames = 30;
  // A camera that disappears is re-opened after 0.5 s, then after twice as
  // long each time it fails, up to this.
  double reconnect_max_interval_s = 30.0;
};

// Where the kiosk keeps what must survive a restart (stages/state_store.hpp).
struct StateConfig {
  std::string dir;  // empty: nothing is kept (the desktop default; the board uses /var/lib/probelight)
};

// The virtual object passed through what the frame went through
// (issue 19): the camera's exposure and white balance, its noise, measured on the tag's cells each frame
// (ibl/sensor_noise.hpp) and added to the object's pixels only
// (stages/noise_match_stage.hpp), and its blur, measured on the tag's
// border (ibl/edge_blur.hpp) and given to the object's edges and texture
// (stages/blur_match_stage.hpp, passes/object_blur.hpp).
struct CameraMatchConfig {
  // The object's light follows the camera's exposure and white balance
  // from the frame the maps were made in to the frame it is drawn over
  // (stages/response_match_stage.hpp).
  bool response = true;
  bool noise = false;
  bool blur = false;
  // As noise_smoothing_new_weight, for the edge's spread (in variance).
  double blur_smoothing_new_weight = 0.3;
  // Each frame's measurement moves the kept one this far toward it: the
  // estimate's own scatter (about 2% of sigma a frame) falls by
  // sqrt(weight / (2 - weight)), to 1% at 0.3, and a change of sensor gain
  // is followed within a few frames.
  double noise_smoothing_new_weight = 0.3;
  // The lens's glare around the object's light above white
  // (passes/object_bloom.hpp): a Gaussian of this spread, in degrees of
  // the field of view (a property of the lens, whatever the resolution).
  bool bloom = false;
  double bloom_sigma_deg = 0.5;
  // While the camera moves, the object smeared along its on-screen
  // velocity over the frame's exposure time (stages/motion_match_stage.hpp).
  bool motion_blur = false;
};

// A virtual lamp lighting the real ground, and the object
// (ibl/virtual_lamp.hpp, passes/virtual_lamp_light.hpp).
struct VirtualLampConfig {
  bool enabled = false;
  ibl::VirtualLamp lamp;
};

struct PipelineSettings {
  EnvironmentMapConfig maps;
  TrackingConfig tracking;
  ObjectConfig object;
  RecalibrationPolicy recalibration;
  MapUpdateSettings map_updates;  // when the maps are rebuilt (map_update_policy.hpp)
  ProbeRefinementConfig probe_refinement;
  LightsConfig lights;
  StateConfig state;
  CameraConfig camera;
  CameraMatchConfig camera_match;
  VirtualLampConfig virtual_lamp;
  bool gpu_finish = true;  // glFinish after each GPU stage so the report times it (costs pipelining)
};

}  // namespace probelight
