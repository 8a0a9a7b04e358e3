// The simulated lens's blur (SceneConfig::lens_blur_sigma_px): a Gaussian
// over the camera's linear light, sampled at whole pixels. Measured on the
// tag's edge seen square-on, where an image row runs along the edge's
// normal: the blur adds its kernel's variance to the edge's spread,
// whatever the pixel's own area gave it before.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "sim/world.hpp"
#include "sim_test_helpers.hpp"

namespace probelight::sim {
namespace {

TEST(LensBlurKernel, IsANormalisedSampledGaussian) {
  for (double sigma : {0.5, 1.0, 1.5, 3.0}) {
    const std::vector<double> kernel = lensBlurKernel(sigma);
    ASSERT_EQ(kernel.size() % 2, 1u);
    double sum = 0.0;
    for (size_t i = 0; i < kernel.size(); ++i) {
      sum += kernel[i];
      EXPECT_DOUBLE_EQ(kernel[i], kernel[kernel.size() - 1 - i]);
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // A sampled Gaussian's variance is sigma^2 to within exp(-2 pi^2
    // sigma^2) (Poisson summation) from sigma 1 on, less what the cut at 4
    // sigma leaves out (0.11% of it); at 0.5 it is 0.215.
    const double variance = lensBlurKernelVariance(kernel);
    if (sigma >= 1.0)
      EXPECT_NEAR(variance, sigma * sigma, 2e-3 * sigma * sigma) << sigma;
    else
      EXPECT_NEAR(variance, 0.215, 0.001);
  }
  EXPECT_EQ(lensBlurKernel(0.0), std::vector<double>{1.0});
}

// The default scene looked at straight down (0.1 degree off, so the
// camera's up is defined), no lens distortion, no noise: the tag's left
// outer edge (white ring | black border) is a column of the image.
SceneConfig squareOnScene(double blur_sigma_px) {
  SceneConfig scene = defaultScene();
  scene.camera.distortion = {0, 0, 0, 0, 0};
  scene.camera_path.look_at_w = glm::dvec3(0.0);
  scene.camera_path.elevation_deg = 89.9;
  scene.camera_path.azimuth_start_deg = -90.0;
  scene.camera_path.azimuth_rate_deg_per_frame = 0.0;
  scene.noise_sigma_code = 0.0;
  scene.lens_blur_sigma_px = blur_sigma_px;
  return scene;
}

// The edge's spread (testing::edgeSpreadVariance) over x0 +- 6 (the white
// ring's outer edge is 12.5 px further out).
double edgeSpreadVariance(const ImageRGB8& image, int x0, int y_begin, int y_end) {
  return testing::edgeSpreadVariance(image, x0, 6, y_begin, y_end);
}

TEST(LensBlur, AddsItsKernelsVarianceToTheEdgesSpread) {
  const SceneConfig sharp_scene = squareOnScene(0.0);
  ImageRGB8 sharp;
  FrameTruth truth;
  World(sharp_scene).render(0, sharp, truth);
  // The edge: x_w = -tag_size / 2, about f 0.05 / 0.6 = 50 px left of the
  // centre; its column is where the sharp frame falls most along the rows.
  const int centre_x = static_cast<int>(sharp_scene.camera.cx_px), centre_y = static_cast<int>(sharp_scene.camera.cy_px);
  int x0 = 0;
  double steepest = 0.0;
  for (int x = centre_x - 60; x < centre_x - 40; ++x) {
    double fall = 0.0;
    for (int y = centre_y - 30; y < centre_y + 30; ++y)
      fall += testing::pixelLinear(sharp, x, y, 1) - testing::pixelLinear(sharp, x + 1, y, 1);
    if (fall > steepest) {
      steepest = fall;
      x0 = x;
    }
  }
  ASSERT_GT(steepest, 60 * 0.3) << "the white ring's fall to the black border must be in view";
  const double sharp_variance = edgeSpreadVariance(sharp, x0, centre_y - 30, centre_y + 30);
  // The pixel's area and the differencing give an edge between pixel
  // centres a sixth of a px^2, one on a pixel boundary (this one: 50 px from
  // the principal point's 319.5) nothing; the blur adds to either.
  EXPECT_LT(sharp_variance, 1.0 / 6.0 + 0.05);
  for (double sigma : {0.5, 1.0, 1.5}) {
    ImageRGB8 blurred;
    World(squareOnScene(sigma)).render(0, blurred, truth);
    const double added = edgeSpreadVariance(blurred, x0, centre_y - 30, centre_y + 30) - sharp_variance;
    const double expected = lensBlurKernelVariance(lensBlurKernel(sigma));
    std::printf("lens blur sigma %.1f: edge spread variance %.3f + %.3f px^2 (kernel %.3f)\n", sigma, sharp_variance,
                added, expected);
    // The black border's 8-bit codes lose the spread's faint tails there
    // (a code step at code 42 is 0.3% of the edge's step): a few percent.
    EXPECT_NEAR(added, expected, 0.1 * expected) << sigma;
  }
}

TEST(LensBlur, AWindowRendersWhatTheWholeFrameHasThere) {
  SceneConfig scene = testing::smallScene();
  scene.lens_blur_sigma_px = 1.2;
  const World world(scene);
  ImageRGB8 whole, part;
  FrameTruth truth;
  world.renderWithOccluders(3, {}, whole, truth);
  World::PixelWindow window{30, 20, 90, 70, false};
  world.renderWithOccluders(3, {}, part, truth, &window);
  int differing = 0, compared = 0;
  for (int y = window.y_begin; y < window.y_end; ++y)
    for (int x = window.x_begin; x < window.x_end; ++x)
      for (int c = 0; c < 3; ++c) {
        ++compared;
        differing += whole.row(y)[3 * x + c] != part.row(y)[3 * x + c];
      }
  EXPECT_EQ(differing, 0) << "of " << compared;
}

}  // namespace
}  // namespace probelight::sim
