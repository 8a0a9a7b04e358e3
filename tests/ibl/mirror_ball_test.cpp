#include "ibl/mirror_ball.hpp"
#include "ibl/probe_to_cube.hpp"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <iostream>
#include <vector>

#include "ibl/camera_projection.hpp"
#include "ibl_test_helpers.hpp"

namespace probelight::ibl {
namespace {

using testing::angleBetweenRad;
using testing::fibonacciDirections;
using testing::kioskBallView;

struct NamedView {
  const char* name;
  MirrorBallView view;
};

// Near and far, with the ball at the image centre and near the frame's corner.
std::vector<NamedView> kioskViews() {
  return {
      {"near centre (20 cm)", kioskBallView(0.20, {319.5, 239.5})},
      {"40 cm centre", kioskBallView(0.40, {319.5, 239.5})},
      {"60 cm centre", kioskBallView(0.60, {319.5, 239.5})},
      {"40 cm frame edge", kioskBallView(0.40, {590.0, 80.0})},
      {"near frame edge (25 cm)", kioskBallView(0.25, {60.0, 420.0})},
      {"far (1.5 m)", kioskBallView(1.5, {200.0, 300.0})},
  };
}

// Pixels across the ball's image out to `fraction` of its silhouette, found
// by projecting ball points whose normals are up to that far from the eye.
std::vector<glm::dvec2> pixelsOnBall(const MirrorBallView& view, double max_angle_from_eye_rad) {
  const glm::dvec3 eye = view.pose.cameraCenterWorld();
  std::vector<glm::dvec2> pixels;
  for (const glm::dvec3& normal : fibonacciDirections(600)) {
    const glm::dvec3 surface = view.center_w + view.radius_m * normal;
    const glm::dvec3 to_eye = glm::normalize(eye - surface);
    // Angle between normal and eye direction: 90 deg is the silhouette.
    if (angleBetweenRad(normal, to_eye) > max_angle_from_eye_rad) continue;
    pixels.push_back(projectToPixel(view.camera, view.pose.toCamera(surface)));
  }
  return pixels;
}

TEST(MirrorBall, PixelToDirectionToPixelRoundTrips) {
  for (const auto& [name, view] : kioskViews()) {
    // Up to 85 deg from the eye: well into the compressed rim.
    const std::vector<glm::dvec2> pixels = pixelsOnBall(view, glm::radians(85.0));
    ASSERT_GT(pixels.size(), 50u) << name;
    std::vector<double> worst_px_by_iterations(9, 0.0);
    for (const glm::dvec2& pixel : pixels) {
      const auto direction = pixelToReflectedDirection(view, pixel);
      ASSERT_TRUE(direction) << name;
      EXPECT_NEAR(glm::length(*direction), 1.0, 1e-12);
      for (int iterations = 0; iterations <= 8; ++iterations) {
        const auto back = reflectedDirectionToPixel(view, *direction, iterations);
        ASSERT_TRUE(back) << name;
        worst_px_by_iterations[iterations] = std::max(worst_px_by_iterations[iterations], glm::length(*back - pixel));
      }
    }
    std::cout << "[ ball px ] " << name << ": worst round-trip error (px) after 0..8 iterations:";
    for (double e : worst_px_by_iterations) std::cout << ' ' << e;
    std::cout << '\n';
    // Newton's steps converge quadratically: two already leave far less than
    // a micro-pixel at every kiosk distance (a plain fixed-point step gains
    // only a factor of radius / (2 distance), and needed 6 steps for this at
    // 20 cm); undistortion contributes ~1e-9 normalised.
    EXPECT_LT(worst_px_by_iterations[2], 1e-6) << name;
    EXPECT_LT(worst_px_by_iterations[8], 1e-6) << name;
    // The shader's 1 step (ProbeToCubeParams::normal_iterations): under
    // 1/50 px even at 20 cm, invisible after bilinear 8-bit sampling (a
    // 1/50 px shift moves a sample by 2% of its neighbour's difference) and
    // below a mediump texture coordinate's step (~0.3 px across 640 px).
    EXPECT_LT(worst_px_by_iterations[ProbeToCubeParams{}.normal_iterations], 0.02) << name;
  }
}

TEST(MirrorBall, DirectionToPixelToDirectionRoundTrips) {
  for (const auto& [name, view] : kioskViews()) {
    const glm::dvec3 away_from_camera = glm::normalize(view.center_w - view.pose.cameraCenterWorld());
    double worst_rad = 0.0;
    int checked = 0;
    for (const glm::dvec3& direction : fibonacciDirections(2000)) {
      // Within ~20 deg of straight behind, the ball's rim compresses directions so
      // much that a 1e-12 px error becomes a large angle; that region is excluded.
      if (angleBetweenRad(direction, away_from_camera) < glm::radians(20.0)) continue;
      const auto pixel = reflectedDirectionToPixel(view, direction);
      ASSERT_TRUE(pixel) << name;
      const auto back = pixelToReflectedDirection(view, *pixel);
      ASSERT_TRUE(back) << name;
      worst_rad = std::max(worst_rad, angleBetweenRad(*back, direction));
      ++checked;
    }
    std::cout << "[ ball dir ] " << name << ": worst direction round trip " << worst_rad << " rad over " << checked
              << " directions (8 iterations)\n";
    // The header promises well below 1e-6 rad at kiosk distances.
    EXPECT_LT(worst_rad, 1e-6) << name;
  }
}

TEST(MirrorBall, SymmetricCasesHaveKnownAnswers) {
  const MirrorBallView view = kioskBallView(0.40, {319.5, 239.5});
  const glm::dvec3 eye = view.pose.cameraCenterWorld();
  const glm::dvec3 toward_camera = glm::normalize(eye - view.center_w);
  // Light returning straight to the camera comes from the point nearest it,
  // which lies on the line to the ball centre, so it images where the centre does.
  const auto back_to_camera = reflectedDirectionToPixel(view, toward_camera);
  ASSERT_TRUE(back_to_camera);
  const glm::dvec3 nearest_point_cam = view.pose.toCamera(view.center_w + view.radius_m * toward_camera);
  const glm::dvec2 expected = projectToPixel(view.camera, nearest_point_cam);
  EXPECT_NEAR(back_to_camera->x, expected.x, 1e-9);
  EXPECT_NEAR(back_to_camera->y, expected.y, 1e-9);
  // Straight away from the camera is the blind spot behind the ball.
  EXPECT_FALSE(reflectedDirectionToPixel(view, -toward_camera));
  // A ray that misses the ball has no reflection.
  EXPECT_FALSE(pixelToReflectedDirection(view, {10.0, 10.0}));
}

TEST(MirrorBall, BallPixelsProjectLikeOpenCv) {
  // The pixel we return must be where cv::projectPoints puts the reflecting point.
  const MirrorBallView view = kioskBallView(0.40, {590.0, 80.0});
  const glm::dvec3 direction = glm::normalize(glm::dvec3(0.2, -0.5, 0.8));
  const auto pixel = reflectedDirectionToPixel(view, direction);
  ASSERT_TRUE(pixel);
  const glm::dvec3 eye = view.pose.cameraCenterWorld();
  // Reconstruct the reflecting point: the normal bisects eye and reflected directions.
  glm::dvec3 normal = glm::normalize(glm::normalize(eye - view.center_w) + direction);
  for (int i = 0; i < 50; ++i) {
    normal = glm::normalize(glm::normalize(eye - (view.center_w + view.radius_m * normal)) + direction);
  }
  const glm::dvec3 surface_w = view.center_w + view.radius_m * normal;
  const glm::dmat3& R = view.pose.R_cam_from_world;
  const cv::Matx33d R_cv(R[0][0], R[1][0], R[2][0], R[0][1], R[1][1], R[2][1], R[0][2], R[1][2], R[2][2]);
  cv::Vec3d rvec;
  cv::Rodrigues(R_cv, rvec);
  const glm::dvec3& t = view.pose.t_cam_from_world;
  std::vector<cv::Point2d> cv_pixel;
  const auto& c = view.camera;
  cv::projectPoints(std::vector<cv::Point3d>{{surface_w.x, surface_w.y, surface_w.z}}, rvec, cv::Vec3d(t.x, t.y, t.z),
                    cv::Matx33d(c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1),
                    std::vector<double>(c.distortion.begin(), c.distortion.end()), cv_pixel);
  // Rodrigues round trip costs ~1e-12 rad, i.e. ~1e-9 px.
  EXPECT_NEAR(pixel->x, cv_pixel[0].x, 1e-6);
  EXPECT_NEAR(pixel->y, cv_pixel[0].y, 1e-6);
}

// Seed A's orthographic approximation against ours, at the kiosk: 3 cm ball
// at 40-60 cm, centred and near the frame edge. Error = angle between the
// direction asked for and the direction the chosen pixel truly shows.
TEST(MirrorBall, OrthographicApproximationIsFarWorseThanOurs) {
  const std::vector<NamedView> views = {
      {"40 cm centre", kioskBallView(0.40, {319.5, 239.5})},
      {"50 cm centre", kioskBallView(0.50, {319.5, 239.5})},
      {"60 cm centre", kioskBallView(0.60, {319.5, 239.5})},
      {"40 cm frame edge", kioskBallView(0.40, {590.0, 80.0})},
      {"60 cm frame edge", kioskBallView(0.60, {40.0, 440.0})},
  };
  for (const auto& [name, view] : views) {
    const glm::dvec3 away_from_camera = glm::normalize(view.center_w - view.pose.cameraCenterWorld());
    double ortho_worst_rad = 0.0, ortho_sum_rad = 0.0, ours_worst_rad = 0.0;
    int count = 0, ortho_misses = 0;
    for (const glm::dvec3& direction : fibonacciDirections(2000)) {
      // Directions the ball shows away from its rim (>= 45 deg from straight behind).
      if (angleBetweenRad(direction, away_from_camera) < glm::radians(45.0)) continue;
      ++count;
      const auto ours_px = reflectedDirectionToPixel(view, direction, ProbeToCubeParams{}.normal_iterations);
      ASSERT_TRUE(ours_px);
      ours_worst_rad = std::max(ours_worst_rad, angleBetweenRad(*pixelToReflectedDirection(view, *ours_px), direction));
      const auto ortho_seen = pixelToReflectedDirection(view, orthographicSphereMapPixel(view, direction));
      if (!ortho_seen) {
        ++ortho_misses;  // the approximation reads off the ball altogether
        continue;
      }
      const double ortho_rad = angleBetweenRad(*ortho_seen, direction);
      ortho_worst_rad = std::max(ortho_worst_rad, ortho_rad);
      ortho_sum_rad += ortho_rad;
    }
    std::cout << "[ ortho vs ours ] " << name << ": orthographic mean " << glm::degrees(ortho_sum_rad / count)
              << " deg, worst " << glm::degrees(ortho_worst_rad) << " deg, " << ortho_misses << "/" << count
              << " off the ball; ours (" << ProbeToCubeParams{}.normal_iterations << " iterations) worst " << glm::degrees(ours_worst_rad) << " deg\n";
    // A 64-px cube face spans 90 deg, ~1.4 deg a texel: the orthographic error
    // is several texels, ours a vanishing fraction of one (1/100 deg is
    // 1/140 of a texel; 1 Newton step leaves 0.0027 deg at 40 cm, where
    // the 2 plain fixed-point steps used before left 0.003 deg).
    EXPECT_GT(ortho_worst_rad, glm::radians(2.0)) << name;
    EXPECT_LT(ours_worst_rad, glm::radians(1e-2)) << name;
    EXPECT_LT(ours_worst_rad * 1000.0, ortho_worst_rad) << name;
  }
}

}  // namespace
}  // namespace probelight::ibl
