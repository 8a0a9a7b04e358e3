#include "app/simulated_world.hpp"

namespace probelight {

RecordedSimulation simulationOf(const SimConfig& sim) {
  RecordedSimulation simulation;
  simulation.environment = sim.env;
  simulation.camera_path = sim.camera_path;
  simulation.noise_sigma_code = sim.noise_sigma;
  simulation.lens_blur_sigma_px = sim.lens_blur_sigma;
  simulation.seed = static_cast<std::uint64_t>(sim.seed);
  simulation.sun_azimuth_rate_deg_per_frame = sim.sun_azimuth_rate_deg_per_frame;
  simulation.environment_rotation_deg = sim.environment_rotation_deg;
  simulation.lamp_on_frame = sim.lamp_on_frame;
  simulation.lamp_off_frame = sim.lamp_off_frame;
  for (int i = 0; i < 3; ++i) simulation.ball_offset_m[i] = sim.ball_offset_m[i];
  return simulation;
}

void applySimulation(const RecordedSimulation& simulation, sim::SceneConfig& scene) {
  scene.environment = simulation.environment;
  scene.camera_path.name = simulation.camera_path;
  scene.noise_sigma_code = simulation.noise_sigma_code;
  scene.lens_blur_sigma_px = simulation.lens_blur_sigma_px;
  scene.seed = simulation.seed;
  scene.lighting.sun_azimuth_rate_deg_per_frame = simulation.sun_azimuth_rate_deg_per_frame;
  scene.environment_rotation_deg = simulation.environment_rotation_deg;
  scene.lighting.lamp_on_frame = simulation.lamp_on_frame;
  scene.lighting.lamp_off_frame = simulation.lamp_off_frame;
  scene.rig.probe_center_w +=
      glm::dvec3(simulation.ball_offset_m[0], simulation.ball_offset_m[1], simulation.ball_offset_m[2]);
}

}  // namespace probelight
