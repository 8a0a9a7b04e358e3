// probelight.yaml: the pipeline's settings. Every field is optional; a file
// only lists what it changes. board/probelight.yaml documents them all.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "app/lighting_state_machine.hpp"

namespace probelight {

struct EnvironmentMapConfig {
  int face_size = 64;           // reflection cube map, texels per face edge
  int diffuse_face_size = 32;   // blur passes and the diffuse map
  double blur_sigma_rad = 0.6;  // a cosine lobe is close to a Gaussian of ~0.6 rad (SEEDS.md)
  int blur_half_taps = 8;
  int normal_iterations = 4;    // fixed-point steps for the ball normal (contraction ~ radius/distance)
  bool force_8bit = false;      // ignore float render-target extensions (tests the GLES2 fallback)
};

struct TrackingConfig {
  double quad_decimate = 2.0;
  int threads = 2;
  double quad_sigma = 0.0;
  bool refine_edges = true;
};

struct ObjectConfig {
  double radius_m = 0.035;             // a sphere resting on the ground
  glm::dvec2 position_w{0.0, 0.0};     // where it rests, in W (metres)
  glm::dvec3 albedo{0.8, 0.8, 0.8};
  double k_specular = 0.25;
  double shininess = 48.0;
  double k_reflect = 0.08;
};

struct SimConfig {
  std::string env = "studio";
  std::string camera_path = "orbit";
  double noise_sigma = 1.5;  // 8-bit code values
  int seed = 1;
  // Lighting that changes during the run (for testing map refresh and
  // recalibration): the environment turning, and a lamp switching.
  double sun_azimuth_rate_deg_per_frame = 0.0;
  int lamp_on_frame = -1;   // -1: never
  int lamp_off_frame = -1;  // -1: stays on
};

struct AppSettings {
  EnvironmentMapConfig maps;
  TrackingConfig tracking;
  ObjectConfig object;
  RecalibrationPolicy recalibration;
  SimConfig sim;
  int save_every = 1;     // write every K-th composited frame; 0 = none
  bool gpu_finish = true;  // glFinish after each GPU stage so the report times it (costs pipelining)
};

// Reads probelight.yaml. Throws config::ConfigError (one line, file + field).
AppSettings loadAppSettings(const std::string& path);

}  // namespace probelight
