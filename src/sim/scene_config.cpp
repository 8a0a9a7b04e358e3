#include "sim/scene_config.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace probelight::sim {

int defaultRenderThreads() {
  constexpr int kDefaultThreads = 2;
  constexpr int kMostThreads = 64;
  const char* text = std::getenv("PROBELIGHT_SIM_THREADS");
  if (text == nullptr || *text == '\0') return kDefaultThreads;
  int threads = 0;
  for (const char* c = text; *c != '\0'; ++c) {
    if (*c < '0' || *c > '9' || threads > kMostThreads) {
      threads = 0;
      break;
    }
    threads = threads * 10 + (*c - '0');
  }
  if (threads < 1 || threads > kMostThreads)
    throw std::invalid_argument("PROBELIGHT_SIM_THREADS: a whole number from 1 to " + std::to_string(kMostThreads) +
                                " expected, got '" + std::string(text) + "'");
  return threads;
}

SceneConfig defaultScene() {
  SceneConfig scene;
  scene.camera.width_px = 640;
  scene.camera.height_px = 480;
  scene.camera.fx_px = 600.0;
  scene.camera.fy_px = 600.0;
  scene.camera.cx_px = 319.5;
  scene.camera.cy_px = 239.5;
  // Mild barrel distortion, like a cheap board camera: about 9 px of
  // displacement at the image corners, under 1 px within 100 px of the centre.
  scene.camera.distortion = {-0.06, 0.015, 0.0, 0.0, 0.0};
  scene.rig = RigGeometry{};
  scene.rig.tag_family = "tag36h11";
  scene.rig.tag_id = 0;
  scene.rig.tag_size_m = 0.10;
  scene.rig.probe_center_w = {0.12, 0.0, 0.08};
  scene.rig.probe_radius_m = 0.03;
  scene.rig.probe_reflectance = 1.0;
  // The pipeline is told the simulated post as it is (scene.post_*).
  scene.rig.post_radius_m = scene.post_radius_m;
  scene.rig.post_albedo = scene.post_albedo;
  return scene;
}

const std::vector<std::string>& environmentNames() {
  static const std::vector<std::string> names = {"sun_sky", "sunrise", "night_street", "studio", "overcast", "coloured_wall", "uniform"};
  return names;
}

const std::vector<std::string>& cameraPathNames() {
  static const std::vector<std::string> names = {"static", "orbit", "slow_wobble", "random", "hand_held_sweep", "pan"};
  return names;
}

}  // namespace probelight::sim

namespace probelight::sim {

std::vector<double> lensBlurKernel(double sigma_px) {
  if (!(sigma_px > 0.0)) return {1.0};
  const int radius = static_cast<int>(std::ceil(4.0 * sigma_px));
  std::vector<double> kernel(static_cast<size_t>(2 * radius + 1));
  double sum = 0.0;
  for (int k = -radius; k <= radius; ++k) {
    const double w = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
    kernel[static_cast<size_t>(k + radius)] = w;
    sum += w;
  }
  for (double& w : kernel) w /= sum;
  return kernel;
}

double lensBlurKernelVariance(const std::vector<double>& kernel) {
  const int radius = static_cast<int>(kernel.size() / 2);
  double variance = 0.0;
  for (int k = -radius; k <= radius; ++k) variance += static_cast<double>(k) * k * kernel[static_cast<size_t>(k + radius)];
  return variance;
}

}  // namespace probelight::sim
