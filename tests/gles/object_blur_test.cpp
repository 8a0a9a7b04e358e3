// The frame's blur given to the object (passes/object_blur): a simulated
// frame with a lens blur, its blur measured on the tag (ibl/edge_blur), a
// flat sphere composited through the blur layer by that much; the sphere's
// silhouette then spreads as the tag's edge does. Both widths are measured
// the same way: a blurred step fitted across the edge, its 10-90% width.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "gles/render_target.hpp"
#include "gles_test_support.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/edge_blur.hpp"
#include "passes/camera_frame_texture.hpp"
#include "passes/environment_maps.hpp"
#include "passes/object_blur.hpp"
#include "passes/object_compositor.hpp"
#include "sim/scene_config.hpp"
#include "sim/world.hpp"

namespace probelight {
namespace {

using test::GpuTest;

constexpr double kTenToNinetyPerSigma = 2.0 * 1.2815515655446004;

TEST(ObjectBlurWeights, AreANormalisedGaussianOfTheSigmaAsked) {
  for (double sigma : {0.4, 1.0, 2.5}) {
    const std::vector<float> w = passes::objectBlurWeights(sigma);
    double sum = w[0], variance = 0.0;
    for (size_t k = 1; k < w.size(); ++k) {
      sum += 2.0 * w[k];
      variance += 2.0 * static_cast<double>(k * k) * w[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6);
    // The weights' own variance is what was asked, below a pixel too
    // (where sampling a Gaussian of that sigma would give too little).
    EXPECT_NEAR(variance, sigma * sigma, 1e-4 * sigma * sigma) << sigma;
  }
  EXPECT_EQ(passes::objectBlurWeights(0.0).size(), 1u);
  EXPECT_EQ(passes::objectBlurWeights(100.0).size(), static_cast<size_t>(passes::kMaxObjectBlurTaps + 1));
  EXPECT_DOUBLE_EQ(passes::objectBlurSigmaPx(0.2), 0.0);
  EXPECT_NEAR(passes::objectBlurSigmaPx(1.0), std::sqrt(1.0 - 1.0 / 12.0), 1e-12);
  EXPECT_DOUBLE_EQ(passes::objectBlurSigmaPx(1.0, 0.0), 1.0);
}

// Phi((d - e) / s) fitted to a radial profile: the spread s by a scan over
// s and e, coarse and then fine around the best (levels fixed).
double fittedSpreadPx(const std::vector<std::pair<double, double>>& samples) {
  auto cost = [&](double s, double e) {
    double sum = 0.0;
    for (const auto& [d, level] : samples) {
      const double r = level - 0.5 * std::erfc(-(d - e) / (s * std::sqrt(2.0)));
      sum += r * r;
    }
    return sum;
  };
  double best_s = 1.0, best_e = 0.0, best = 1e300;
  auto scan = [&](double s0, double s1, double s_step, double e0, double e1, double e_step) {
    const double s_from = best_s, e_from = best_e;
    for (double s = s_from + s0; s <= s_from + s1; s += s_step)
      for (double e = e_from + e0; e <= e_from + e1; e += e_step)
        if (s > 0.02) {
          const double c = cost(s, e);
          if (c < best) {
            best = c;
            best_s = s;
            best_e = e;
          }
        }
  };
  scan(-0.95, 3.0, 0.05, -1.0, 1.0, 0.1);
  scan(-0.05, 0.05, 0.002, -0.1, 0.1, 0.01);
  return best_s;
}

// A flat sphere (0.6 linear, shaded by ambient light alone) over a uniform
// grey frame (code 60), the camera 0.6 m away on the sphere's axis with no
// distortion: its silhouette is a circle of radius f R / sqrt(D^2 - R^2)
// about the principal point. Drawn through `blur` into `target`.
struct FlatSphereOverGrey {
  static constexpr double kRadiusM = 0.04, kDistanceM = 0.6, kInsideLinear = 0.6;
  static constexpr std::uint8_t kGreyCode = 60;
  CameraIntrinsics camera;
  glm::dvec3 centre_w{0.0, 0.0, 0.04};
  PoseCamFromWorld pose;
  double radius_px = 0.0;
  gles::RenderTarget target;
  passes::CameraFrameTexture background;
  passes::EnvironmentMaps maps;
  passes::ObjectCompositor compositor;
  passes::ObjectBlurLayer blur;
  ibl::SurfaceMaterial flat;
  ibl::SceneLighting lighting;

  bool init(const CameraIntrinsics& scene_camera, std::string& error) {
    camera = scene_camera;
    camera.distortion = {0, 0, 0, 0, 0};
    pose = test::lookAt(centre_w + glm::dvec3(0.0, -kDistanceM * 0.8, kDistanceM * 0.6), centre_w);
    radius_px = camera.fx_px * kRadiusM / std::sqrt(kDistanceM * kDistanceM - kRadiusM * kRadiusM);
    const gles::Capabilities& caps = test::sharedCapabilities();
    if (!target.init(camera.width_px, camera.height_px, error) || !background.init(caps, error) ||
        !maps.init(caps, {}, error) || !compositor.init(caps, {}, maps.storage(), error) ||
        !blur.init(camera.width_px, camera.height_px, ibl::CameraTransfer{}, error))
      return false;
    ImageRGB8 grey;
    grey.resize(camera.width_px, camera.height_px);
    std::fill(grey.pixels.begin(), grey.pixels.end(), kGreyCode);
    flat.ambient = 1.0f;
    flat.k_diffuse = 0.0f;
    lighting.ambient_rgb = glm::vec3(static_cast<float>(kInsideLinear));
    return background.upload(grey, error);
  }
  // The frame: the grey, then the sphere at `at_w` through the blur layer
  // over `region` with `sigma_px` and `smear_px` (and `noise`, if any).
  bool draw(const glm::dvec3& at_w, const passes::PixelRect& region, double sigma_px, const glm::dvec2& smear_px,
            ImageRGB8& out, std::string& error, const passes::SensorNoiseMatch* noise = nullptr,
            const passes::SensorNoiseTexture* noise_texture = nullptr) {
    target.bind();
    compositor.drawCameraBackground(background);
    blur.beginObject(region, sigma_px, smear_px);
    return compositor.drawSphereObject(camera, pose, at_w, kRadiusM, flat, lighting, maps, error) &&
           blur.composite(noise, noise_texture, error) && target.readRGB(out, error);
  }
  // Linear light between the grey (0) and the sphere (1), green.
  static double level(const ImageRGB8& image, int x, int y) {
    const double outside = ibl::srgbToLinear(kGreyCode / 255.0);
    return (ibl::srgbToLinear(image.row(y)[3 * x + 1] / 255.0) - outside) / (kInsideLinear - outside);
  }
};

class BlurredObject : public GpuTest, public ::testing::WithParamInterface<double> {};

TEST_P(BlurredObject, SilhouetteSpreadsAsTheTagsEdge) {
  // The frame's blur, from the tag of a simulated frame with this lens.
  sim::SceneConfig scene = sim::defaultScene();
  scene.lens_blur_sigma_px = GetParam();
  const sim::World world(scene);
  ImageRGB8 frame;
  FrameTruth truth;
  world.render(0, frame, truth);
  const ibl::EdgeBlurReading tag = ibl::measureEdgeBlur(
      scene.camera, truth.pose, scene.rig.tag_size_m / 2.0, scene.rig.tag_size_m / 8.0,
      [&frame](int x, int y) {
        const std::uint8_t* p = frame.row(y) + 3 * x;
        return glm::u8vec3(p[0], p[1], p[2]);
      },
      ibl::EdgeBlurSettings{});
  ASSERT_EQ(tag.status, ibl::EdgeBlurStatus::kMeasured) << tag.message;

  FlatSphereOverGrey rig;
  std::string error;
  ASSERT_TRUE(rig.init(scene.camera, error)) << error;
  const CameraIntrinsics& camera = rig.camera;
  const double radius_px = rig.radius_px;
  const glm::dvec2 centre_px(camera.cx_px, camera.cy_px);
  // The sphere is drawn one sample a pixel: its own edge has no spread, so
  // it takes the tag's whole.
  const double sigma_px = passes::objectBlurSigmaPx(tag.edge_sigma_px, 0.0);
  const int reach = static_cast<int>(radius_px) + 3;
  const passes::PixelRect region{static_cast<int>(centre_px.x) - reach, static_cast<int>(centre_px.y) - reach,
                                 2 * reach, 2 * reach};
  ImageRGB8 out;
  ASSERT_TRUE(rig.draw(rig.centre_w, region, sigma_px, glm::dvec2(0.0), out, error)) << error;

  // The silhouette's radial profile, in linear light, normalised between the
  // grey (0) and the sphere (1).
  std::vector<std::pair<double, double>> samples;
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x) {
      const double d = radius_px - glm::length(glm::dvec2(x, y) - centre_px);  // + inside
      if (std::abs(d) > 6.0) continue;
      samples.emplace_back(d, FlatSphereOverGrey::level(out, x, y));
    }
  ASSERT_GT(samples.size(), 1000u);
  const double object_spread = fittedSpreadPx(samples);
  const double tag_width = kTenToNinetyPerSigma * tag.edge_sigma_px, object_width = kTenToNinetyPerSigma * object_spread;
  std::printf("lens sigma %.1f: tag edge 10-90%% %.2f px (s %.3f), object silhouette %.2f px (s %.3f), blur added %.3f px\n",
              GetParam(), tag_width, tag.edge_sigma_px, object_width, object_spread, sigma_px);
  EXPECT_NEAR(object_width, tag_width, 0.3);

  // With the frame's noise matched too, it goes in after the blur: the
  // object's interior scatters by the noise asked, not by a blurred
  // fraction of it. The difference from the noiseless composite holds the
  // noise and both composites' rounding: sigma^2 + 2/12.
  passes::SensorNoiseMatch noise;
  noise.model.dark_code = glm::dvec3(0.0);
  noise.model.bright_code = glm::dvec3(255.0);
  noise.model.dark_sigma_code = noise.model.bright_sigma_code = glm::dvec3(2.0);
  passes::SensorNoiseTexture noise_texture;
  ASSERT_TRUE(noise_texture.init(error)) << error;
  ImageRGB8 noisy;
  ASSERT_TRUE(rig.draw(rig.centre_w, region, sigma_px, glm::dvec2(0.0), noisy, error, &noise, &noise_texture)) << error;
  double sum2 = 0.0;
  int interior = 0, outside_changed = 0;
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x) {
      const double r = glm::length(glm::dvec2(x, y) - centre_px);
      const double d = double(noisy.row(y)[3 * x + 1]) - double(out.row(y)[3 * x + 1]);
      if (r < 0.8 * radius_px) {
        sum2 += d * d;
        ++interior;
      } else if (r > radius_px + 4.0 * sigma_px + 2.0) {
        outside_changed += d != 0.0;
      }
    }
  const double scatter = std::sqrt(sum2 / interior);
  // ~5000 pixels: sigma's standard error is 1%.
  EXPECT_NEAR(scatter, std::sqrt(4.0 + 2.0 / 12.0), 0.15 * std::sqrt(4.0 + 2.0 / 12.0));
  EXPECT_EQ(outside_changed, 0);
}

INSTANTIATE_TEST_SUITE_P(LensBlur, BlurredObject, ::testing::Values(0.5, 1.0, 1.5));

}  // namespace
}  // namespace probelight

namespace probelight {
namespace {

TEST(MotionSmearTaps, KeepTheirSpacingUnderAPixelAndSpanTheSmear) {
  for (const glm::dvec2 smear : {glm::dvec2(0.6, 0.0), glm::dvec2(7.0, -3.0), glm::dvec2(0.0, 32.5)}) {
    const passes::MotionSmearTaps taps = passes::motionSmearTaps(smear);
    const double spacing = glm::length(taps.step_px);
    EXPECT_LT(spacing, 1.0) << smear.x << "," << smear.y;
    // 2 taps + 1 samples at the middles of as many parts of the smear.
    EXPECT_NEAR(spacing * (2 * taps.taps + 1), glm::length(smear), 1e-9);
  }
  EXPECT_EQ(passes::motionSmearTaps(glm::dvec2(0.0)).taps, 0);
  EXPECT_EQ(passes::motionSmearTaps(glm::dvec2(std::nan(""), 1.0)).taps, 0);
  EXPECT_EQ(passes::motionSmearTaps(glm::dvec2(500.0, 0.0)).taps, passes::kMaxMotionSmearTaps);
}

// The camera's motion over the exposure, given to the object: a flat disk
// composited through the blur layer with a smear must be the same disk
// drawn sharp and then averaged, on the CPU, over the smear's continuous
// segment (in linear light, bilinear between pixel centres). The midpoint
// rule over 2 taps + 1 samples under a pixel apart errs by at most
// h^2 / (8 L) per kink of the bilinear profile (h the spacing, L the
// smear's length; a sharp edge's profile has a kink a pixel, two on the
// segment's way across it): 0.03 at L = 9.8, with the layers' 8-bit
// rounding (half a code a pass) on top.
class SmearedObject : public GpuTest {};

TEST_F(SmearedObject, IsTheSharpObjectAveragedAlongTheSmear) {
  FlatSphereOverGrey rig;
  std::string error;
  ASSERT_TRUE(rig.init(sim::defaultScene().camera, error)) << error;
  const CameraIntrinsics& camera = rig.camera;
  const glm::dvec2 smear_px(9.0, -4.0);  // right and up the image
  // The object's bounds, tight as the compose stage's (projectedBounds, 2 px margin).
  const int reach = static_cast<int>(std::ceil(rig.radius_px)) + 2;
  const passes::PixelRect region{static_cast<int>(camera.cx_px) - reach, static_cast<int>(camera.cy_px) - reach,
                                 2 * reach, 2 * reach};
  // Compared over the region grown past all the smear can reach.
  const int margin = 12;
  // An earlier frame's object 25 px to the right (0.025 m at 0.6 m and
  // f 600), smeared too, drawn over its own region: the layers keep it
  // where this frame does not write, and none of it may be read into this
  // frame's (a moving object's old place bleeding in).
  const glm::dvec3 earlier_w = rig.centre_w + glm::dvec3(0.025, 0.0, 0.0);
  const passes::PixelRect earlier_region{region.x + 25, region.y, region.width, region.height};
  ImageRGB8 sharp, smeared, earlier;
  ASSERT_TRUE(rig.draw(earlier_w, earlier_region, 0.0, smear_px, earlier, error)) << error;
  ASSERT_TRUE(rig.draw(rig.centre_w, region, 0.0, glm::dvec2(0.0), sharp, error)) << error;
  ASSERT_TRUE(rig.draw(earlier_w, earlier_region, 0.0, smear_px, earlier, error)) << error;
  ASSERT_TRUE(rig.draw(rig.centre_w, region, 0.0, smear_px, smeared, error)) << error;

  auto level = [](const ImageRGB8& image, int x, int y) { return FlatSphereOverGrey::level(image, x, y); };
  auto bilinear = [&](double x, double y) {
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    return (1 - fy) * ((1 - fx) * level(sharp, x0, y0) + fx * level(sharp, x0 + 1, y0)) +
           fy * ((1 - fx) * level(sharp, x0, y0 + 1) + fx * level(sharp, x0 + 1, y0 + 1));
  };
  constexpr int kSegmentSamples = 400;
  double worst = 0.0, worst_mirrored = 0.0, sum_sharp = 0.0, sum_smeared = 0.0;
  int changed_outside = 0;
  for (int y = region.y - margin; y < region.y + region.height + margin; ++y)
    for (int x = region.x - margin; x < region.x + region.width + margin; ++x) {
      double expected = 0.0, mirrored = 0.0;
      for (int m = 0; m < kSegmentSamples; ++m) {
        const double t = (m + 0.5) / kSegmentSamples - 0.5;
        expected += bilinear(x - t * smear_px.x, y - t * smear_px.y);
        mirrored += bilinear(x - t * smear_px.x, y + t * smear_px.y);
      }
      expected /= kSegmentSamples;
      mirrored /= kSegmentSamples;
      const double got = level(smeared, x, y);
      worst = std::max(worst, std::abs(got - expected));
      worst_mirrored = std::max(worst_mirrored, std::abs(got - mirrored));
      sum_sharp += level(sharp, x, y);
      sum_smeared += got;
    }
  for (int y = 0; y < camera.height_px; ++y)
    for (int x = 0; x < camera.width_px; ++x)
      if (x < region.x - margin || x >= region.x + region.width + margin || y < region.y - margin ||
          y >= region.y + region.height + margin)
        changed_outside += smeared.row(y)[3 * x + 1] != sharp.row(y)[3 * x + 1];
  std::printf("smear (%.0f, %.0f) px: worst %.4f of the contrast against the CPU's (%.4f with the smear mirrored), "
              "light kept %.4f\n",
              smear_px.x, smear_px.y, worst, worst_mirrored, sum_smeared / sum_sharp);
  EXPECT_LT(worst, 0.03);
  // The direction matters: up-right is not down-right.
  EXPECT_GT(worst_mirrored, 0.2);
  // Averaging moves light, it neither makes nor loses it.
  EXPECT_NEAR(sum_smeared / sum_sharp, 1.0, 0.005);
  EXPECT_EQ(changed_outside, 0);
}

}  // namespace
}  // namespace probelight
