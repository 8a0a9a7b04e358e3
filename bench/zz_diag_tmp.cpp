// TEMPORARY diagnostic, to be deleted.
#include <benchmark/benchmark.h>
#include <cmath>
#include <cstdio>
#include "ibl/cube_map.hpp"
#include "ibl/probe_to_cube.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
using namespace probelight;
static double lum(const glm::dvec3& c) { return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b; }
static void run(const char* label, sim::SceneConfig scene, std::uint64_t frame_index, int face) {
  sim::World world(scene);
  ImageRGB8 rgb; FrameTruth truth;
  world.render(frame_index, rgb, truth);
  ibl::MirrorBallView view{scene.camera, truth.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
  ibl::ProbeToCubeParams p; p.face_size = face;
  auto map = ibl::probeImageToCubeMap(view, rgb, p);
  glm::dvec3 to_cam = glm::normalize(truth.pose.cameraCenterWorld() - scene.rig.probe_center_w);
  double c100 = std::cos(100.0 * M_PI / 180), c60 = std::cos(60.0 * M_PI / 180);
  double asky=0,tsky=0,agr=0,tgr=0; double a100 = 0, t100 = 0, a60 = 0, t60 = 0, asm_ = 0, tsm = 0, adark=0,tdark=0, abr=0,tbr=0, bias=0; int nsm = 0, n100 = 0;
  for (int f = 0; f < 6; ++f) for (int y = 0; y < face; ++y) for (int x = 0; x < face; ++x) {
    glm::dvec3 d = ibl::cubeTexelCenterDirection(f, x, y, face);
    double c = glm::dot(d, to_cam);
    if (c < c100) continue;
    double tv = lum(world.radiance(d, frame_index).clipped);
    double ev = lum(glm::dvec3(map.texel(f, x, y)));
    double e = std::abs(ev - tv);
    a100 += e; t100 += tv; ++n100; bias += ev - tv;
    if (c >= c60) { a60 += e; t60 += tv; }
    if (d.z >= 0) { asky += e; tsky += tv; } else { agr += e; tgr += tv; }
    // smoothness: truth within ~4 deg
    glm::dvec3 u = glm::normalize(glm::cross(d, std::abs(d.z) < 0.9 ? glm::dvec3(0,0,1) : glm::dvec3(1,0,0)));
    glm::dvec3 v = glm::cross(d, u);
    double k = 0.07, mx = tv, mn = tv;
    for (glm::dvec3 o : {u, -u, v, -v}) { double s = lum(world.radiance(glm::normalize(d + k * o), frame_index).clipped); mx = std::max(mx, s); mn = std::min(mn, s); }
    if (mx - mn < 0.1 * std::max(tv, 0.02)) { asm_ += e; tsm += tv; ++nsm; }
    if (tv < 0.2) { adark += e; tdark += tv; } else { abr += e; tbr += tv; }
  }
  std::printf("%-34s r=%.1fpx err100=%.1f%% err60=%.1f%% smooth(%.0f%% of texels)=%.1f%% dark(<0.2) abs share=%.0f%% bias/mean=%+.1f%% meanTruth=%.3f | sky(z>=0)=%.1f%% ground=%.1f%% ground share of abs=%.0f%%\n",
              label, truth.probe_radius_px, 100 * a100 / t100, 100 * a60 / t60, 100.0 * nsm / n100, 100 * asm_ / tsm,
              100 * adark / a100, 100 * bias / t100, t100 / n100, 100*asky/tsky, 100*agr/tgr, 100*agr/a100);
}
static void BM_diag(benchmark::State& state) {
  for (auto _ : state) {}
  sim::SceneConfig base = sim::defaultScene(); base.environment = "studio";
  for (std::uint64_t fr : {0, 60, 120, 180}) { char l[64]; std::snprintf(l, 64, "default frame %llu", (unsigned long long)fr); run(l, base, fr, 64); }
  { auto s = base; s.noise_sigma_code = 0; run("noise 0", s, 0, 64); }
  { auto s = base; s.noise_sigma_code = 0; s.supersample_per_axis = 4; run("noise 0, ss 4", s, 0, 64); }
  { auto s = base; s.noise_sigma_code = 0; s.camera_path.distance_m = 0.3; run("noise 0, dist 0.3", s, 0, 64); }
  { auto s = base; s.noise_sigma_code = 0; s.camera_path.distance_m = 0.3; run("noise 0, dist 0.3, face 128", s, 0, 128); }
  { auto s = base; s.noise_sigma_code = 0; s.camera_path.distance_m = 0.2; run("noise 0, dist 0.2, face 128", s, 0, 128); }
  { auto s = base; s.noise_sigma_code = 0; s.environment = "uniform"; run("uniform env, noise 0", s, 0, 64); }
  { auto s = base; s.noise_sigma_code = 0; s.environment = "overcast"; run("overcast env, noise 0", s, 0, 64); }
  { auto s = base; s.environment = "sun_sky"; run("sun_sky env", s, 0, 64); }
}
BENCHMARK(BM_diag)->Iterations(1);
