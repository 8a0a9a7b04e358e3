#include "tracking/robust_line_fit.hpp"

#include <algorithm>
#include <cmath>

namespace probelight::tracking {

namespace {

struct WeightedLine {
  glm::dvec2 centroid;
  glm::dvec2 normal;  // unit
  double distanceTo(const glm::dvec2& p) const { return std::abs(glm::dot(normal, p - centroid)); }
};

// The weighted total-least-squares line: through the weighted centroid,
// along the scatter matrix's major axis.
std::optional<WeightedLine> weightedFit(const std::vector<glm::dvec2>& points, const std::vector<double>& weights) {
  double total = 0.0;
  glm::dvec2 centroid(0.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    total += weights[i];
    centroid += weights[i] * points[i];
  }
  if (!(total > 0.0)) return std::nullopt;
  centroid /= total;
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::dvec2 d = points[i] - centroid;
    sxx += weights[i] * d.x * d.x;
    sxy += weights[i] * d.x * d.y;
    syy += weights[i] * d.y * d.y;
  }
  // Major eigenvalue of [[sxx, sxy], [sxy, syy]]; of the two eigenvector
  // forms, the longer one is the better conditioned.
  const double half_difference = 0.5 * (sxx - syy);
  const double major = 0.5 * (sxx + syy) + std::sqrt(half_difference * half_difference + sxy * sxy);
  const glm::dvec2 from_first_row(sxy, major - sxx), from_second_row(major - syy, sxy);
  const glm::dvec2 direction =
      glm::dot(from_first_row, from_first_row) >= glm::dot(from_second_row, from_second_row) ? from_first_row
                                                                                           : from_second_row;
  const double length = glm::length(direction);
  // No spread at all (coincident points): no direction to fit.
  if (!(length > 1e-300) || !std::isfinite(length)) return std::nullopt;
  return WeightedLine{centroid, glm::dvec2(-direction.y, direction.x) / length};
}

// Reweights by `weightOf(distance)` and refits until the line stops moving.
template <typename WeightOf>
WeightedLine iterate(const std::vector<glm::dvec2>& points, WeightedLine line, std::vector<double>& weights,
                     const RobustLineFitSettings& settings, WeightOf weightOf) {
  for (int iteration = 0; iteration < settings.max_iterations; ++iteration) {
    for (std::size_t i = 0; i < points.size(); ++i) weights[i] = weightOf(line.distanceTo(points[i]));
    const std::optional<WeightedLine> next = weightedFit(points, weights);
    if (!next) break;  // every weight 0 (or no spread left): keep the last line
    // The normal's sign is arbitrary: compare with it aligned to the last one.
    const glm::dvec2 normal = glm::dot(next->normal, line.normal) < 0.0 ? -next->normal : next->normal;
    const double moved = std::abs(glm::dot(normal, next->centroid - line.centroid));
    const double turned = glm::length(normal - line.normal);
    line = WeightedLine{next->centroid, normal};
    if (moved < settings.tolerance && turned < settings.tolerance) break;
  }
  return line;
}

double medianOf(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

double medianDistance(const std::vector<glm::dvec2>& points, const WeightedLine& line, std::vector<double>& scratch) {
  scratch.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) scratch[i] = line.distanceTo(points[i]);
  return medianOf(scratch);
}

}  // namespace

std::optional<glm::dvec3> fitLineRobust(const std::vector<glm::dvec2>& points, const RobustLineFitSettings& settings) {
  const std::size_t n = points.size();
  if (n < 2) return std::nullopt;
  for (const glm::dvec2& p : points)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return std::nullopt;

  // 1. The start: of the lines through point pairs half the set apart, the
  //    one with the least median distance (least median of squares over a
  //    deterministic set of candidates). Half of the points may be bad, in a
  //    block or scattered, and some pair still joins two good ones.
  std::vector<double> scratch;
  std::optional<WeightedLine> start;
  double start_median = 0.0;
  // At most kCandidates pairs, spread evenly: with a quarter of the points
  // bad at random, all 16 miss a good pair with odds of 1e-8 (each is good
  // with odds (3/4)^2); a block of bad points spoils only the pairs that
  // start in it or half the set before it.
  constexpr std::size_t kCandidates = 16;
  const std::size_t half = n / 2;
  const std::size_t starts = n - half;
  const std::size_t candidates = std::min(starts, kCandidates);
  for (std::size_t c = 0; c < candidates; ++c) {
    const std::size_t i = c * starts / candidates;
    const glm::dvec2 along = points[i + half] - points[i];
    const double length = glm::length(along);
    if (!(length > 0.0)) continue;
    const WeightedLine candidate{points[i], glm::dvec2(-along.y, along.x) / length};
    // The candidate's median (the (n/2 + 1)-th smallest distance) beats the
    // best one exactly when at least n/2 + 1 distances are below it: a count
    // decides, and only a winner's median is found (nth_element's branches
    // cost several times the counting's arithmetic).
    if (start) {
      std::size_t below = 0;
      for (const glm::dvec2& p : points) below += candidate.distanceTo(p) < start_median ? 1 : 0;
      if (below < n / 2 + 1) continue;
    }
    start = candidate;
    start_median = medianDistance(points, candidate, scratch);
  }
  if (!start) return std::nullopt;  // all points coincide

  // 2. Tukey's biweight from there, with the start's scale (Rousseeuw's
  //    small-sample factor for least median of squares), then once more with
  //    the scale of the residuals about the line found.
  std::vector<double> weights(n, 1.0);
  auto biweight = [&](const WeightedLine& from, double scale_px) {
    const double cutoff_px = settings.tukey_cutoff_sigmas * std::max(settings.min_scale_px, scale_px);
    return iterate(points, from, weights, settings, [cutoff_px](double distance) {
      if (distance >= cutoff_px) return 0.0;
      const double u = distance / cutoff_px;
      return (1.0 - u * u) * (1.0 - u * u);
    });
  };
  const double small_sample = n > 2 ? 1.0 + 5.0 / static_cast<double>(n - 2) : 1.0;
  const WeightedLine first = biweight(*start, 1.4826 * small_sample * start_median);
  const WeightedLine line = biweight(first, 1.4826 * medianDistance(points, first, scratch));
  return glm::dvec3(line.normal, -glm::dot(line.normal, line.centroid));
}

}  // namespace probelight::tracking
