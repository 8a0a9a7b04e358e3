// A straight line through 2D points that ignores the bad ones (a speck, the
// post's shadow across part of a tag edge, a sample that straddles a corner):
//   1. The start: of 16 lines through point pairs half the set apart, the
//      one with the least median distance to the points (least median of
//      squares over a deterministic set of candidates); up to half the
//      points may be bad in a block, a good share of them scattered.
//   2. Tukey's biweight by iteratively reweighted total least squares, with
//      its cut-off at tukey_cutoff_sigmas times the residuals' robust scale
//      (1.4826 x their median): points beyond it get no weight at all, the
//      inliers keep 95% efficiency against Gaussian noise. Twice: with the
//      start's scale, then with the scale about the line found.
//
// This replaces cv::fitLine(DIST_HUBER), which restarts a Huber fit 20 times
// from random 10-point subsets and keeps the line with the least sum of
// distances. Against the truth this is as accurate or better in every case
// the tests try (a quarter of an edge in shadow: 0.02 px where OpenCV is
// 0.17 px off), deterministic by construction, and a fraction of the work:
// cv::fitLine was half the corner refinement's instructions
// (scripts/bench-instructions.sh).
#pragma once

#include <optional>
#include <vector>

#include <glm/glm.hpp>

namespace probelight::tracking {

struct RobustLineFitSettings {
  double tukey_cutoff_sigmas = 4.685;  // the biweight's 95%-efficiency constant
  // The scale's floor: exact (noise-free) points have a zero median residual,
  // which would cut every point off. Far below an edge sample's noise.
  double min_scale_px = 1e-3;
  int max_iterations = 30;  // per stage
  // Converged when the line moves by less than this at the points' centroid
  // and its unit normal turns by less than this.
  double tolerance = 1e-9;
};

// The line a x + b y + c = 0 with (a, b) a unit normal; empty for fewer than
// 2 points, non-finite points, or points that do not span a direction.
std::optional<glm::dvec3> fitLineRobust(const std::vector<glm::dvec2>& points, const RobustLineFitSettings& settings = {});

}  // namespace probelight::tracking
