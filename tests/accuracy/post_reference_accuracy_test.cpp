// The ball's post read in simulated frames (ibl::readPost) against the
// irradiance the simulator lit it with (World::postIrradiance), over worlds
// and views: what the post reference divides the border's light by.
//
// Tolerance: each reading averages N >= 3 pixels of 8-bit codes with the
// simulator's sensor noise (1.5 codes); near a code c the sRGB decode turns
// one code into about 2.4 / c of the linear value, so a reading's noise is
// 2.4 * 1.5 / (c * sqrt(N)): three of those, plus 1% for the pose's error
// in the normals and the codes' rounding, for any one reading (the truth is
// averaged over the same pixels' normals). On average 1.5%.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "accuracy_test_support.hpp"
#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/post_reference.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

using testing::luminance;

TEST(PostReference, ReadsTheIrradianceTheSimulatorLitThePostWith) {
  const std::string data = PROBELIGHT_TEST_DATA_DIR;
  const std::vector<std::string> worlds = {"sun_sky", "studio", "overcast", data + "/env/StageEnvLatLong.exr"};
  struct View {
    const char* name;
    double distance_m, elevation_deg, azimuth_deg;
  };
  const View views[] = {{"near", 0.45, 45.0, -90.0}, {"far", 0.8, 30.0, -70.0}, {"side", 0.55, 38.0, 160.0}};
  double sum = 0.0, worst = 0.0;
  int readings = 0;
  for (const std::string& environment : worlds)
    for (const View& view : views) {
      const sim::SceneConfig scene =
          testing::staticView(environment, view.distance_m, view.elevation_deg, view.azimuth_deg);
      const sim::World world(scene);
      ImageRGB8 frame;
      FrameTruth truth;
      world.render(0, frame, truth);
      const tracking::TagTrackResult track = testing::trackRendered(scene, frame);
      ASSERT_TRUE(track.found) << track.status;
      const ibl::RgbPixelReader read = [&](int x, int y) {
        const std::uint8_t* p = frame.row(y) + 3 * x;
        return glm::u8vec3(p[0], p[1], p[2]);
      };
      const ibl::PostReading post = ibl::readPost(scene.camera, track.pose, scene.rig, read, {});
      const std::string where = environment.substr(environment.find_last_of('/') + 1) + " " + view.name;
      ASSERT_EQ(post.status, ibl::PostStatus::kMeasured) << where << ": " << post.message;
      double view_worst = 0.0;
      for (const ibl::DiffuseReference& reference : post.references) {
        double expected = 0.0;
        for (const glm::dvec3& normal : reference.pixel_normals_w)
          expected += luminance(world.postIrradiance(normal, 0)) / static_cast<double>(reference.pixel_normals_w.size());
        const double error = std::abs(luminance(reference.irradiance_rgb) - expected) / expected;
        const double code = 255.0 * ibl::linearToSrgb(expected * scene.post_albedo / M_PI);
        const double tolerance = 0.01 + 3.0 * 2.4 * 1.5 / (code * std::sqrt(static_cast<double>(reference.pixels)));
        EXPECT_LE(error, tolerance) << where << " normal azimuth "
                                    << glm::degrees(std::atan2(reference.normal_w.y, reference.normal_w.x)) << ", "
                                    << reference.pixels << " pixels at code " << code;
        view_worst = std::max(view_worst, error);
        sum += error;
        ++readings;
      }
      worst = std::max(worst, view_worst);
      std::printf("[ post     ] %-22s %zu readings from %d pixels, worst %.2f%%\n", where.c_str(),
                  post.references.size(), post.pixels_seen, 100.0 * view_worst);
    }
  std::printf("[ post     ] %d readings: mean %.2f%%, worst %.2f%%\n", readings, 100.0 * sum / readings, 100.0 * worst);
  EXPECT_LE(sum / readings, 0.015);
}

// Where the rig has no post, or the post is out of the frame, or narrower
// than a pixel, nothing is read and the status says which.
TEST(PostReference, SaysWhyItReadsNothing) {
  sim::SceneConfig scene = sim::defaultScene();
  scene.camera_path.name = "static";
  const sim::World world(scene);
  ImageRGB8 frame;
  FrameTruth truth;
  world.render(0, frame, truth);
  const ibl::RgbPixelReader read = [&](int x, int y) {
    const std::uint8_t* p = frame.row(y) + 3 * x;
    return glm::u8vec3(p[0], p[1], p[2]);
  };
  RigGeometry no_post = scene.rig;
  no_post.post_radius_m = 0.0;
  EXPECT_EQ(ibl::readPost(scene.camera, truth.pose, no_post, read, {}).status, ibl::PostStatus::kNoPost);
  RigGeometry unknown_albedo = scene.rig;
  unknown_albedo.post_albedo = 0.0;
  EXPECT_EQ(ibl::readPost(scene.camera, truth.pose, unknown_albedo, read, {}).status, ibl::PostStatus::kNoPost);
  RigGeometry short_post = scene.rig;
  short_post.probe_center_w.z = 1.5 * short_post.probe_radius_m;  // half a radius of post under the ball
  EXPECT_EQ(ibl::readPost(scene.camera, truth.pose, short_post, read, {}).status, ibl::PostStatus::kNoPost);
  RigGeometry thin = scene.rig;
  thin.post_radius_m = 0.0004;  // under a pixel across at 0.5 m
  const ibl::PostReading thin_reading = ibl::readPost(scene.camera, truth.pose, thin, read, {});
  EXPECT_EQ(thin_reading.status, ibl::PostStatus::kNotInView);
  EXPECT_NE(thin_reading.message.find("thin"), std::string::npos) << thin_reading.message;
  RigGeometry elsewhere = scene.rig;
  elsewhere.probe_center_w.x += 5.0;  // far out of the frame
  EXPECT_EQ(ibl::readPost(scene.camera, truth.pose, elsewhere, read, {}).status, ibl::PostStatus::kNotInView);
  // All white: every bin clipped.
  const ibl::RgbPixelReader white = [](int, int) { return glm::u8vec3(255); };
  EXPECT_EQ(ibl::readPost(scene.camera, truth.pose, scene.rig, white, {}).status, ibl::PostStatus::kClipped);
  const ibl::RgbPixelReader black = [](int, int) { return glm::u8vec3(0); };
  EXPECT_EQ(ibl::readPost(scene.camera, truth.pose, scene.rig, black, {}).status, ibl::PostStatus::kTooDark);
}

}  // namespace
}  // namespace probelight
