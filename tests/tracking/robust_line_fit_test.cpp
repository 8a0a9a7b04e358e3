// fitLineRobust against the true line, side by side with OpenCV's
// cv::fitLine(DIST_HUBER), which the corner refiner used before.
#include "tracking/robust_line_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace probelight::tracking {
namespace {

// Distance of p from the line l (unit normal).
double distanceTo(const glm::dvec3& l, const glm::dvec2& p) { return std::abs(l.x * p.x + l.y * p.y + l.z); }

// Points along a tag edge as the corner refiner gives them: 48 samples 2 px
// apart (a 94 px edge), at an arbitrary angle and place in a 640x480 frame.
struct Edge {
  glm::dvec2 start, direction;
  std::vector<glm::dvec2> points;
  glm::dvec2 normal() const { return {-direction.y, direction.x}; }
  // The fitted line's worst distance from the true edge at its two ends
  // (the corners, which is what the refiner intersects the lines for).
  double endError(const glm::dvec3& line) const {
    return std::max(distanceTo(line, start), distanceTo(line, start + 94.0 * direction));
  }
};
Edge randomEdge(std::mt19937& rng, double noise_px) {
  std::uniform_real_distribution<double> position(50.0, 590.0), angle(0.0, 2.0 * M_PI);
  std::normal_distribution<double> noise(0.0, noise_px);
  Edge edge;
  edge.start = {position(rng), position(rng) * 0.75};
  const double a = angle(rng);
  edge.direction = {std::cos(a), std::sin(a)};
  for (int i = 0; i < 48; ++i) edge.points.push_back(edge.start + (2.0 * i) * edge.direction + noise(rng) * edge.normal());
  return edge;
}

glm::dvec3 openCvHuberLine(const std::vector<glm::dvec2>& points) {
  glm::dvec2 mean(0.0);
  for (const glm::dvec2& p : points) mean += p / static_cast<double>(points.size());
  std::vector<cv::Point2f> centred;  // as the refiner called it: float, centred
  for (const glm::dvec2& p : points) centred.emplace_back(static_cast<float>(p.x - mean.x), static_cast<float>(p.y - mean.y));
  cv::Vec4f line;
  cv::fitLine(centred, line, cv::DIST_HUBER, 0.0, 1e-4, 1e-4);
  const double px = line[2] + mean.x, py = line[3] + mean.y;
  return {-line[1], line[0], line[1] * px - line[0] * py};
}

TEST(RobustLineFit, PointsOnALineGiveThatLineWithAUnitNormal) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Edge edge = randomEdge(rng, 0.0);
    const std::optional<glm::dvec3> line = fitLineRobust(edge.points);
    ASSERT_TRUE(line);
    EXPECT_NEAR(std::hypot(line->x, line->y), 1.0, 1e-12);
    // Exact data: only rounding of ~600 px coordinates remains.
    for (const glm::dvec2& p : edge.points) EXPECT_LT(distanceTo(*line, p), 1e-9);
  }
}

// Each case: 300 random edges with sensor-like noise, some samples pushed
// off the edge. The mean end error must be no worse than OpenCV's, and
// within what the inliers' noise allows: a line fitted to n samples of
// noise sigma is off by ~sigma * 2 / sqrt(n) at its ends (the lever of the
// end over the centroid is sqrt(3) times the rms lever), so 0.3 sigma for 48
// samples, and the outliers may add no more than a few hundredths of a px.
TEST(RobustLineFit, AtLeastAsCloseToTheTruthAsOpenCvsHuberFit) {
  struct Case {
    const char* what;
    double noise_px;
    int bad;
    bool in_a_block;  // contiguous (a shadow along part of the edge) or scattered (specks)
    double bad_min_px, bad_max_px;
    double max_mean_error_px;
  };
  const Case cases[] = {
      {"no bad samples, noise 0.02 px", 0.02, 0, false, 0.0, 0.0, 0.3 * 0.02 + 0.005},
      {"3 specks 3-8 px off, noise 0.2 px", 0.2, 3, false, 3.0, 8.0, 0.3 * 0.2 + 0.02},
      {"a quarter of the edge 1-2 px off, noise 0.05 px", 0.05, 12, true, 1.0, 2.0, 0.3 * 0.05 + 0.02},
      {"6 samples 0.2-0.5 px off, noise 0.05 px", 0.05, 6, false, 0.2, 0.5, 0.3 * 0.05 + 0.02},
  };
  for (const Case& c : cases) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> pick(0, 47);
    std::uniform_real_distribution<double> offset(c.bad_min_px, c.bad_max_px);
    double ours_sum = 0.0, opencv_sum = 0.0;
    constexpr int kEdges = 300;
    for (int trial = 0; trial < kEdges; ++trial) {
      Edge edge = randomEdge(rng, c.noise_px);
      const int block_start = pick(rng) % (48 - c.bad + 1);
      for (int k = 0; k < c.bad; ++k)
        edge.points[static_cast<std::size_t>(c.in_a_block ? block_start + k : pick(rng))] += offset(rng) * edge.normal();
      const std::optional<glm::dvec3> ours = fitLineRobust(edge.points);
      ASSERT_TRUE(ours) << c.what;
      ours_sum += edge.endError(*ours);
      opencv_sum += edge.endError(openCvHuberLine(edge.points));
    }
    const double ours_mean = ours_sum / kEdges, opencv_mean = opencv_sum / kEdges;
    std::printf("[ line fit ] %-48s mean error at the ends: ours %.4f px, cv::fitLine %.4f px\n", c.what, ours_mean,
                opencv_mean);
    EXPECT_LE(ours_mean, opencv_mean) << c.what;
    EXPECT_LT(ours_mean, c.max_mean_error_px) << c.what;
  }
}

// Up to half the points bad in one block: the start still finds the good half.
TEST(RobustLineFit, AlmostHalfTheEdgeOffDoesNotMoveTheLine) {
  std::vector<glm::dvec2> points;
  for (int i = 0; i < 48; ++i) points.emplace_back(2.0 * i, 100.0 + (i < 22 ? 3.0 : 0.0));
  const std::optional<glm::dvec3> line = fitLineRobust(points);
  ASSERT_TRUE(line);
  EXPECT_LT(distanceTo(*line, {0.0, 100.0}), 1e-9);
  EXPECT_LT(distanceTo(*line, {94.0, 100.0}), 1e-9);
}

TEST(RobustLineFit, DegenerateInputIsRefused) {
  EXPECT_FALSE(fitLineRobust({}));
  EXPECT_FALSE(fitLineRobust({{1.0, 2.0}}));
  EXPECT_FALSE(fitLineRobust({{1.0, 2.0}, {1.0, 2.0}, {1.0, 2.0}}));
  EXPECT_FALSE(fitLineRobust({{1.0, 2.0}, {NAN, 3.0}, {4.0, 5.0}}));
  EXPECT_FALSE(fitLineRobust({{1.0, 2.0}, {INFINITY, 3.0}, {4.0, 5.0}}));
  // Two distinct points do define a line.
  const std::optional<glm::dvec3> line = fitLineRobust({{0.0, 0.0}, {3.0, 4.0}});
  ASSERT_TRUE(line);
  EXPECT_NEAR(distanceTo(*line, {6.0, 8.0}), 0.0, 1e-12);
}

}  // namespace
}  // namespace probelight::tracking
