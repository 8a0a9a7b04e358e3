// Irradiance accuracy of the whole map path (tag → pose → GPU reflection map →
// diffuse map) against the simulator's truth, over worlds and views the
// pipeline was not tuned on: both real HDR worlds, sunny, overcast, studio and
// coloured scenes, each from a near, a far and an off-centre view, on 8-bit
// frames with noise.
//
// The reference is the truth of the *clipped* environment: what an 8-bit
// camera can know through the ball. The figures are printed as the table in
// docs/accuracy.md, for both diffuse methods (the cosine passes on the GPU, and
// SH9 projected from the read-back reflection map) and four reflection face
// sizes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gles/capabilities.hpp"
#include "gles/egl_context.hpp"
#include "accuracy_test_support.hpp"
#include "ibl/probe_outline.hpp"
#include "ibl/spherical_harmonics.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "sim/camera_path.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

using testing::luminance;

// The 14 normals of analysis.json: ±X, ±Y, ±Z and the 8 diagonals.
std::vector<glm::dvec3> fourteenNormals() {
  std::vector<glm::dvec3> normals = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int x : {1, -1})
    for (int y : {1, -1})
      for (int z : {1, -1}) normals.push_back(glm::normalize(glm::dvec3(x, y, z)));
  return normals;
}

struct IrradianceViewCase {
  const char* name;
  double distance_m;
  double elevation_deg;
  double azimuth_deg;
  glm::dvec3 look_offset_w;  // added to the default look-at point: moves the ball off-centre
};

struct ErrorSummary {
  double mean = 0.0;   // over the 14 normals
  double worst = 0.0;  // the worst normal
};

struct Accumulated {
  double sum_of_means = 0.0;
  double worst = 0.0;
  int cases = 0;
  void add(const ErrorSummary& e) {
    sum_of_means += e.mean;
    worst = std::max(worst, e.worst);
    ++cases;
  }
};

class IrradianceAccuracy : public testing::GpuSuite {};

TEST_F(IrradianceAccuracy, FourteenNormalsAcrossWorldsViewsAndFaceSizes) {
  const std::vector<std::string> environments = {
      "sun_sky", "overcast", "studio", "coloured_wall",
      std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/KernerEnvLatLong.exr",
      std::string(PROBELIGHT_TEST_DATA_DIR) + "/env/StageEnvLatLong.exr"};
  // Near, far, and the ball pushed toward the frame's right edge.
  const IrradianceViewCase views[] = {{"near 0.45 m", 0.45, 45.0, -90.0, {0, 0, 0}},
                            {"far 0.8 m", 0.8, 30.0, -70.0, {0, 0, 0}},
                            {"ball off-centre", 0.55, 38.0, -110.0, {-0.09, 0.05, 0}}};
  const int face_sizes[] = {16, 32, 64, 128};
  const int default_face_size = passes::EnvironmentMapSettings{}.reflection_face_size;
  const gles::Capabilities capabilities = gles::probeCapabilities();

  std::map<int, Accumulated> cosine_by_face, sh9_by_face;
  std::printf("\n| environment | view | ball radius px | cosine passes: mean / worst | SH9: mean / worst |\n"
              "|---|---|---|---|---|\n");
  for (const std::string& environment : environments) {
    for (const IrradianceViewCase& view : views) {
      sim::SceneConfig scene = sim::defaultScene();
      scene.environment = environment;
      scene.camera_path.name = "static";
      scene.camera_path.distance_m = view.distance_m;
      scene.camera_path.elevation_deg = view.elevation_deg;
      scene.camera_path.azimuth_start_deg = view.azimuth_deg;
      scene.camera_path.look_at_w = sim::defaultLookAt(scene.rig) + view.look_offset_w;
      const sim::World world(scene);
      ImageRGB8 frame;
      FrameTruth truth;
      world.render(0, frame, truth);
      ASSERT_TRUE(truth.probe_fully_visible && truth.tag_fully_visible) << environment << " " << view.name;
      std::vector<double> truth_luminance;
      for (const glm::dvec3& normal : fourteenNormals())
        truth_luminance.push_back(luminance(world.irradiance(normal, 0).clipped));

      std::vector<std::uint8_t> luma;
      lumaFromRgb(frame, luma);
      tracking::TagTracker tracker(tracking::TagDetectorSettings{}, scene.rig, scene.camera);
      const tracking::TagTrackResult track = tracker.track(luma.data(), frame.width, frame.height, frame.width);
      ASSERT_TRUE(track.found) << environment << " " << view.name << ": " << track.status;
      const ibl::MirrorBallView ball{scene.camera, track.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};

      std::string error;
      passes::CameraFrameTexture texture;
      ASSERT_TRUE(texture.init(capabilities, error) && texture.upload(frame, error)) << error;
      for (int face_size : face_sizes) {
        passes::EnvironmentMapSettings settings;
        settings.reflection_face_size = face_size;
        settings.glossy_levels = 0;  // only the diffuse map is measured here
        passes::EnvironmentMaps maps;
        ASSERT_TRUE(maps.init(capabilities, settings, error)) << error;
        ASSERT_TRUE(maps.updateReflection(texture, ball, scene.rig.probe_reflectance, error)) << error;
        ASSERT_TRUE(maps.updateDiffuse(error)) << error;
        const std::optional<ibl::CubeMapRGB> diffuse = maps.readDiffuse(error);
        std::vector<float> validity;
        const std::optional<ibl::CubeMapRGB> reflection = maps.readReflection(error, &validity);
        ASSERT_TRUE(diffuse && reflection) << error;
        const ibl::SH9RGB sh9 = ibl::projectToSH9(*reflection, &validity);

        ErrorSummary cosine, spherical;
        const std::vector<glm::dvec3> normals = fourteenNormals();
        for (size_t k = 0; k < normals.size(); ++k) {
          const double expected = truth_luminance[k];
          const double by_cosine = M_PI * luminance(glm::dvec3(diffuse->sampleBilinear(normals[k])));
          const double by_sh9 = luminance(ibl::irradianceFromSH9(sh9, normals[k]));
          const double cosine_error = std::abs(by_cosine - expected) / expected;
          const double sh9_error = std::abs(by_sh9 - expected) / expected;
          cosine.mean += cosine_error / normals.size();
          cosine.worst = std::max(cosine.worst, cosine_error);
          spherical.mean += sh9_error / normals.size();
          spherical.worst = std::max(spherical.worst, sh9_error);
        }
        cosine_by_face[face_size].add(cosine);
        sh9_by_face[face_size].add(spherical);
        if (face_size == default_face_size) {
          const std::string short_name = environment.substr(environment.find_last_of('/') + 1);
          std::printf("| %s | %s | %.1f | %.1f%% / %.1f%% | %.1f%% / %.1f%% |\n", short_name.c_str(), view.name,
                      ibl::computeProbeOutline(ball).radius_px, 100.0 * cosine.mean, 100.0 * cosine.worst,
                      100.0 * spherical.mean, 100.0 * spherical.worst);
        }
      }
    }
  }

  std::printf("\n| reflection faces | cosine passes: mean / worst normal | SH9: mean / worst normal |\n|---|---|---|\n");
  for (int face_size : face_sizes) {
    const Accumulated& c = cosine_by_face[face_size];
    const Accumulated& s = sh9_by_face[face_size];
    std::printf("| %d² | %.2f%% / %.1f%% | %.2f%% / %.1f%% |\n", face_size, 100.0 * c.sum_of_means / c.cases,
                100.0 * c.worst, 100.0 * s.sum_of_means / s.cases, 100.0 * s.worst);
  }

  // The bounds for the default path: mean relative error <= 4%, no
  // normal worse than 15%. A per-pixel exact-geometry estimate from one 8-bit
  // frame gets about 3% mean on such scenes; the brute-force integral of our
  // own reflection map is within 1-7% per normal, so the cosine passes add
  // little on top of the probe.
  const Accumulated& by_default = cosine_by_face[default_face_size];
  ASSERT_EQ(by_default.cases, 18);
  EXPECT_LE(by_default.sum_of_means / by_default.cases, 0.04);
  EXPECT_LE(by_default.worst, 0.15);
  // SH9 cannot represent a lamp's sharp terminator (ringing of up to 3/32 of
  // the lamp's power there), so it gets the same bounds only on the mean.
  const Accumulated& sh9_default = sh9_by_face[default_face_size];
  EXPECT_LE(sh9_default.sum_of_means / sh9_default.cases, 0.04);
}

}  // namespace
}  // namespace probelight
