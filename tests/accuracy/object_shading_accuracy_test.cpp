// Issue 7's object figure, in rendered frames: a diffuse sphere drawn by the
// GPU stages (the 8-bit diffuse map, plus the clipped lights a bracket, the
// tag's white border, or the border with the ball's post found) against
// the simulator's own frame of a
// real sphere in the same place (World::renderWithOccluders: Lambertian,
// lit by the full-HDR irradiance at each normal). Both in camera-linear
// units; the mean relative difference over the sphere's pixels.
//
// Albedo 0.2 keeps both spheres below the clip (their sun-facing sides
// would clip at 0.8, and a clipped pixel says nothing); the simulator's
// truth frame is rendered without sensor noise, so that the figure is the
// pipeline's error, not the noise of one frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "accuracy_test_support.hpp"
#include "stages/bracket_merge.hpp"
#include "core/apriltag_families.hpp"
#include "gles/capabilities.hpp"
#include "gles/render_target.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/post_reference.hpp"
#include "ibl/white_reference.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/object_compositor.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {
namespace {

using testing::luminance;

glm::dvec3 linearAt(const ImageRGB8& image, int x, int y) {
  const std::uint8_t* p = image.row(y) + 3 * x;
  return {ibl::srgbToLinear(p[0] / 255.0), ibl::srgbToLinear(p[1] / 255.0), ibl::srgbToLinear(p[2] / 255.0)};
}

class ObjectShadingAccuracy : public testing::GpuSuite {};

TEST_F(ObjectShadingAccuracy, DiffuseSphereAgainstTheSimulatorsHdrLitSphere) {
  const std::string data = PROBELIGHT_TEST_DATA_DIR;
  const std::vector<std::pair<std::string, std::string>> worlds = {
      {"sun_sky", "sun_sky"},
      {"overcast", "overcast"},
      {"studio", "studio"},
      {"Kerner (real)", data + "/env/KernerEnvLatLong.exr"},
      {"Stage (real)", data + "/env/StageEnvLatLong.exr"}};
  const gles::Capabilities capabilities = gles::probeCapabilities();
  sim::VirtualOccluder sphere;
  sphere.position_w = {-0.10, 0.06};
  sphere.radius_m = 0.035;
  sphere.albedo = glm::dvec3(0.2);
  std::printf("\n| world | sphere pixels | shading vs HDR-lit sphere: bracket / white border / white border + post / 8-bit | clipped lights: bracket / border | post |\n"
              "|---|---|---|---|---|\n");
  double sums[4] = {0.0, 0.0, 0.0, 0.0};
  int worlds_counted = 0;
  for (const auto& [name, environment] : worlds) {
    sim::SceneConfig scene = sim::defaultScene();
    scene.environment = environment;
    scene.rig.probe_reflectance = 0.7;
    scene.camera_path.name = "static";
    const sim::World world(scene);
    sim::SceneConfig noiseless = scene;
    noiseless.noise_sigma_code = 0.0;
    const sim::World truth_world(noiseless);
    ImageRGB8 frame, truth_frame;
    FrameTruth truth;
    world.render(0, frame, truth);
    truth_world.renderWithOccluders(0, {sphere}, truth_frame, truth);

    std::vector<std::uint8_t> luma;
    lumaFromRgb(frame, luma);
    tracking::TagTracker tracker(tracking::TagDetectorSettings{}, scene.rig, scene.camera);
    const tracking::TagTrackResult track = tracker.track(luma.data(), frame.width, frame.height, frame.width);
    ASSERT_TRUE(track.found) << track.status;
    const ibl::MirrorBallView ball{scene.camera, track.pose, scene.rig.probe_center_w, scene.rig.probe_radius_m};
    const ibl::ProbeOutline outline = ibl::computeProbeOutline(ball);

    // The kiosk's stages: 8-bit maps from the frame.
    std::string error;
    passes::CameraFrameTexture texture;
    ASSERT_TRUE(texture.init(capabilities, error) && texture.upload(frame, error)) << error;
    passes::EnvironmentMaps maps;
    passes::EnvironmentMapSettings map_settings;
    map_settings.glossy_levels = 0;
    ASSERT_TRUE(maps.init(capabilities, map_settings, error)) << error;
    ASSERT_TRUE(maps.updateReflection(texture, ball, scene.rig.probe_reflectance, error)) << error;
    ASSERT_TRUE(maps.updateDiffuse(error)) << error;
    std::vector<float> validity;
    const std::optional<ibl::CubeMapRGB> reflection = maps.readReflection(error, &validity);
    ASSERT_TRUE(reflection) << error;
    const ibl::HdrMergeSettings merge;
    const double clip_level = ibl::srgbToLinear(merge.clip_code / 255.0) / scene.rig.probe_reflectance;
    const ibl::RgbPixelReader read = [&](int x, int y) {
      const std::uint8_t* p = frame.row(y) + 3 * x;
      return glm::u8vec3(p[0], p[1], p[2]);
    };
    const std::vector<std::uint8_t> mask = ibl::clippedTexelMask(ball, read, merge.clip_code, reflection->face_size);

    // The bracket, as `run` takes it.
    std::vector<BracketCandidate> candidates;
    const ImageRGB8* last = &frame;
    for (double ev = -3.0; ev >= -15.0 && ballPixelCodes(*last, outline, merge).clipped > 0; ev -= 3.0) {
      BracketCandidate candidate{"EV", ev, {}};
      FrameTruth ignored;
      world.render(0, candidate.rgb, ignored, ev);
      candidates.push_back(std::move(candidate));
      last = &candidates.back().rgb;
    }
    std::vector<ibl::ClippedLight> bracket_lights;
    if (!candidates.empty()) {
      const BracketSetup setup{ball, outline, scene.rig, tracking::TagDetectorSettings{}, merge, reflection->face_size};
      const BracketMergeResult merged = mergeBracketProbe(frame, std::move(candidates), setup, nullptr);
      ASSERT_TRUE(merged.hdr_cube) << merged.status;
      bracket_lights = ibl::clippedLights(*merged.hdr_cube, *reflection, &validity, clip_level, &mask);
    }
    // The white border, from the frame alone.
    const AprilTagFamilyHandle family = createAprilTagFamily(scene.rig.tag_family);
    const ibl::WhiteBorderReading border = ibl::readWhiteBorder(
        scene.camera, track.pose,
        ibl::tagWhiteRing(family->width_at_border, family->reversed_border, scene.rig.tag_size_m), read, {});
    ibl::CubeMapRGB corrected = *reflection;
    const ibl::WhiteReferenceResult white =
        ibl::correctClippedWithWhiteBorder(corrected, &validity, border, scene.rig.tag_white_albedo, clip_level, &mask);
    std::vector<ibl::ClippedLight> white_lights, post_lights;
    ibl::PostReading post;
    ibl::DiffuseFit post_fit;
    if (white.status == ibl::WhiteReferenceStatus::kCorrected) {
      white_lights = ibl::clippedLights(corrected, *reflection, &validity, clip_level, &mask);
      // And the post beside it (the simulated rig describes its post).
      ibl::CubeMapRGB refined = corrected;
      const ibl::PostCorrection correction = ibl::correctClippedWithPost(
          refined, *reflection, &validity, clip_level, &mask, border, scene.rig, scene.camera, track.pose, read, {});
      post = correction.reading;
      post_fit = correction.fit;
      post_lights = ibl::clippedLights(refined, *reflection, &validity, clip_level, &mask);
    }

    // Draw the sphere three ways over a black frame, and once in flat white
    // for its coverage.
    passes::ObjectCompositor compositor;
    gles::RenderTarget target;
    passes::CameraFrameTexture black_texture;
    ImageRGB8 black;
    black.resize(frame.width, frame.height);
    ASSERT_TRUE(compositor.init(capabilities, {}, maps.storage(), error) &&
                target.init(frame.width, frame.height, error) && black_texture.init(capabilities, error) &&
                black_texture.upload(black, error))
        << error;
    const glm::dvec3 centre_w(sphere.position_w, sphere.radius_m);
    auto draw = [&](const ibl::SurfaceMaterial& material, const ibl::SceneLighting& lighting) {
      target.bind();
      compositor.drawCameraBackground(black_texture);
      std::string draw_error;
      EXPECT_TRUE(compositor.drawSphereObject(scene.camera, track.pose, centre_w, sphere.radius_m, material, lighting,
                                              maps, draw_error))
          << draw_error;
      ImageRGB8 image;
      EXPECT_TRUE(target.readRGB(image, draw_error)) << draw_error;
      return image;
    };
    ibl::SurfaceMaterial lambertian;
    lambertian.albedo = glm::vec3(0.2f);
    lambertian.k_diffuse = 1.0f;
    lambertian.k_specular = 0.0f;
    lambertian.k_reflect = 0.0f;
    lambertian.ambient = 0.0f;
    auto lightingWith = [](const std::vector<ibl::ClippedLight>& lights) {
      ibl::SceneLighting lighting;
      for (std::size_t k = 0; k < lights.size() && k < lighting.clipped_direction_w.size(); ++k) {
        lighting.clipped_direction_w[k] = glm::vec3(lights[k].direction_w);
        lighting.clipped_diffuse_rgb[k] = glm::vec3(lights[k].irradiance_rgb / M_PI);
      }
      return lighting;
    };
    const ImageRGB8 drawn[4] = {draw(lambertian, lightingWith(bracket_lights)), draw(lambertian, lightingWith(white_lights)),
                                draw(lambertian, ibl::SceneLighting{}), draw(lambertian, lightingWith(post_lights))};
    ibl::SurfaceMaterial flat;
    flat.ambient = 1.0f;
    flat.k_diffuse = flat.k_specular = flat.k_reflect = 0.0f;
    ibl::SceneLighting white_ambient;
    white_ambient.ambient_rgb = glm::vec3(1.0f);
    const ImageRGB8 coverage = draw(flat, white_ambient);
    // Inside the sphere by 3 px: its edge pixels mix sphere and background.
    cv::Mat inside(frame.height, frame.width, CV_8U, cv::Scalar(0));
    for (int y = 0; y < frame.height; ++y)
      for (int x = 0; x < frame.width; ++x) inside.at<std::uint8_t>(y, x) = coverage.row(y)[3 * x] > 128 ? 255 : 0;
    cv::erode(inside, inside, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7)));

    double error_sum[4] = {0.0, 0.0, 0.0, 0.0};
    int pixels = 0, clipped = 0;
    for (int y = 0; y < frame.height; ++y)
      for (int x = 0; x < frame.width; ++x) {
        if (!inside.at<std::uint8_t>(y, x)) continue;
        const std::uint8_t* t = truth_frame.row(y) + 3 * x;
        if (std::max({t[0], t[1], t[2]}) >= merge.clip_code) {
          ++clipped;
          continue;
        }
        const double expected = luminance(linearAt(truth_frame, x, y));
        if (expected <= 0.0) continue;
        for (int k = 0; k < 4; ++k) error_sum[k] += std::abs(luminance(linearAt(drawn[k], x, y)) - expected) / expected;
        ++pixels;
      }
    ASSERT_GT(pixels, 500) << name;
    EXPECT_LT(clipped, pixels / 50) << name << ": albedo 0.2 should keep the real sphere below the clip";
    std::printf("| %s | %d | %.1f%% / %.1f%% / %.1f%% / %.1f%% | %zu / %zu | %s |\n", name.c_str(), pixels,
                100.0 * error_sum[0] / pixels, 100.0 * error_sum[1] / pixels, 100.0 * error_sum[3] / pixels,
                100.0 * error_sum[2] / pixels, bracket_lights.size(), white_lights.size(),
                white.status == ibl::WhiteReferenceStatus::kCorrected
                    ? (std::string(ibl::toString(post.status)) + ", " + std::to_string(post.references.size()) +
                       " normals, " + ibl::toString(post_fit.status)).c_str()
                    : "not read (border not used)");
    for (int k = 0; k < 4; ++k) sums[k] += error_sum[k] / pixels;
    ++worlds_counted;
    // The bound with a bracket, in every world.
    EXPECT_LE(error_sum[0] / pixels, 0.10) << name;
    // With one clipped source the border's single number places all the
    // missing light where it belongs: as good as a bracket there. (Several
    // sources of unequal brightness it can only share out by solid angle;
    // those figures are reported, see docs/accuracy.md.)
    if (white_lights.size() == 1) {
      EXPECT_LE(error_sum[1] / pixels, 0.10) << name;
    }
    // With the post beside the border, which reads the irradiance at the
    // normals the camera sees: the bracket's bound, in every world.
    EXPECT_LE(error_sum[3] / pixels, 0.10) << name;
  }
  std::printf("\nmean over %d worlds: bracket %.1f%%, white border %.1f%%, white border + post %.1f%%, 8-bit %.1f%%\n",
              worlds_counted, 100.0 * sums[0] / worlds_counted, 100.0 * sums[1] / worlds_counted,
              100.0 * sums[3] / worlds_counted, 100.0 * sums[2] / worlds_counted);
  // Light past the clip matters: without it the sphere is far off.
  EXPECT_GE(sums[2] / worlds_counted, 0.3);
  // The single-frame bound, met with the border and the post.
  EXPECT_LE(sums[3] / worlds_counted, 0.20);
}

}  // namespace
}  // namespace probelight
