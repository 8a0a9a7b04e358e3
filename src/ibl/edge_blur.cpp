#include "ibl/edge_blur.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

namespace {

constexpr double kPixelAreaVariancePx2 = 1.0 / 12.0;
constexpr double kTenToNinetyPerSigma = 2.0 * 1.2815515655446004;  // 2 x Phi^-1(0.9)

double standardNormalCdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
double standardNormalPdf(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2.0 * 3.14159265358979323846); }

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

struct Sample {
  double across_px;  // + toward the ring (outside the square)
  double linear;
};

struct SideFit {
  double offset_px = 0.0;
  double sigma_px = 0.0;
  double inside_level = 0.0, outside_level = 0.0;
  double rms_residual_of_step = 1.0;  // the fit's rms residual over |outside - inside|
  bool converged = false;
};

// Solves the 4 x 4 system a x = b in place (Gaussian elimination with
// partial pivoting); false when singular.
bool solve4(std::array<std::array<double, 4>, 4> a, std::array<double, 4> b, std::array<double, 4>& x) {
  for (int col = 0; col < 4; ++col) {
    int pivot = col;
    for (int row = col + 1; row < 4; ++row)
      if (std::abs(a[row][col]) > std::abs(a[pivot][col])) pivot = row;
    if (!(std::abs(a[pivot][col]) > 1e-300)) return false;
    std::swap(a[col], a[pivot]);
    std::swap(b[col], b[pivot]);
    for (int row = col + 1; row < 4; ++row) {
      const double f = a[row][col] / a[col][col];
      for (int k = col; k < 4; ++k) a[row][k] -= f * a[col][k];
      b[row] -= f * b[col];
    }
  }
  for (int row = 3; row >= 0; --row) {
    double sum = b[row];
    for (int k = row + 1; k < 4; ++k) sum -= a[row][k] * x[k];
    x[row] = sum / a[row][row];
  }
  return true;
}

// inside + (outside - inside) Phi((d - e) / s) to the samples, by
// Levenberg-Marquardt in (inside, outside, e, s): the levels are fitted
// too, since within a cell's reach a wide blur never settles to them.
SideFit fitBlurredStep(const std::vector<Sample>& samples, double reach_px, double inside_guess, double outside_guess) {
  SideFit fit;
  std::array<double, 4> p = {inside_guess, outside_guess, 0.0, 0.7};
  auto cost = [&](const std::array<double, 4>& q) {
    double sum = 0.0;
    for (const Sample& sample : samples) {
      const double r = sample.linear - (q[0] + (q[1] - q[0]) * standardNormalCdf((sample.across_px - q[2]) / q[3]));
      sum += r * r;
    }
    return sum;
  };
  double current = cost(p), lambda = 1e-3;
  for (int iteration = 0; iteration < 100; ++iteration) {
    std::array<std::array<double, 4>, 4> jtj{};
    std::array<double, 4> jtr{};
    for (const Sample& sample : samples) {
      const double z = (sample.across_px - p[2]) / p[3];
      const double cdf = standardNormalCdf(z), pdf = standardNormalPdf(z), step = p[1] - p[0];
      const double r = sample.linear - (p[0] + step * cdf);
      const std::array<double, 4> j = {1.0 - cdf, cdf, -step * pdf / p[3], -step * pdf * z / p[3]};
      for (int a = 0; a < 4; ++a) {
        jtr[a] += j[a] * r;
        for (int b = 0; b < 4; ++b) jtj[a][b] += j[a] * j[b];
      }
    }
    for (int a = 0; a < 4; ++a) jtj[a][a] *= 1.0 + lambda;
    std::array<double, 4> delta{};
    if (!solve4(jtj, jtr, delta)) break;
    std::array<double, 4> tried = p;
    for (int a = 0; a < 4; ++a) tried[a] += delta[a];
    tried[2] = std::clamp(tried[2], -reach_px, reach_px);
    tried[3] = std::clamp(tried[3], 0.05, reach_px);
    const double tried_cost = cost(tried);
    if (tried_cost <= current) {
      double moved = 0.0;
      for (int a = 0; a < 4; ++a) moved = std::max(moved, std::abs(tried[a] - p[a]));
      p = tried;
      current = tried_cost;
      lambda = std::max(lambda * 0.3, 1e-12);
      if (moved < 1e-7) {
        fit.converged = true;
        break;
      }
    } else {
      lambda *= 10.0;
      if (lambda > 1e10) {
        fit.converged = true;  // no step lowers the cost: at a minimum
        break;
      }
    }
  }
  fit.inside_level = p[0];
  fit.outside_level = p[1];
  fit.offset_px = p[2];
  fit.sigma_px = p[3];
  const double step = std::abs(p[1] - p[0]);
  fit.rms_residual_of_step =
      samples.empty() || !(step > 0.0) ? 1.0 : std::sqrt(current / static_cast<double>(samples.size())) / step;
  return fit;
}

}  // namespace

const char* toString(EdgeBlurStatus status) {
  switch (status) {
    case EdgeBlurStatus::kMeasured: return "measured";
    case EdgeBlurStatus::kNotInView: return "not_in_view";
    case EdgeBlurStatus::kTooSmall: return "too_small";
    case EdgeBlurStatus::kNoEdge: return "no_edge";
  }
  return "unknown";
}

EdgeBlurReading measureEdgeBlur(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, double border_half_m,
                                double cell_m, const RgbPixelReader& read_pixel, const EdgeBlurSettings& settings) {
  EdgeBlurReading reading;
  if (!(border_half_m > 0.0) || !(cell_m > 0.0)) {
    reading.message = "no tag border to measure the blur on";
    return reading;
  }
  const glm::dmat3 world_from_cam = glm::transpose(pose.R_cam_from_world);
  const glm::dvec3 eye_w = pose.cameraCenterWorld();
  auto project = [&](const glm::dvec2& point_w, glm::dvec2& pixel) {
    const glm::dvec3 point_cam = pose.toCamera(glm::dvec3(point_w, 0.0));
    if (!(point_cam.z > 1e-6)) return false;
    pixel = projectToPixel(camera, point_cam);
    return std::isfinite(pixel.x) && std::isfinite(pixel.y);
  };
  auto inFrame = [&](const glm::dvec2& p) {
    return p.x >= 0.0 && p.y >= 0.0 && p.x <= camera.width_px - 1.0 && p.y <= camera.height_px - 1.0;
  };
  double pooled_variance = 0.0;
  int sides_in_view = 0, sides_too_small = 0, sides_without_edge = 0;
  // Each side: its middle point, its direction, and the outward normal.
  const std::array<std::array<glm::dvec2, 3>, 4> sides = {{{{{-border_half_m, 0.0}, {0.0, 1.0}, {-1.0, 0.0}}},
                                                          {{{border_half_m, 0.0}, {0.0, 1.0}, {1.0, 0.0}}},
                                                          {{{0.0, -border_half_m}, {1.0, 0.0}, {0.0, -1.0}}},
                                                          {{{0.0, border_half_m}, {1.0, 0.0}, {0.0, 1.0}}}}};
  const double half_length_m = settings.side_middle_fraction * border_half_m;
  for (const auto& [middle_w, along_w, out_w] : sides) {
    glm::dvec2 middle_px, along_px, out_px;
    constexpr double kDelta_m = 1e-4;
    if (!project(middle_w, middle_px) || !project(middle_w + kDelta_m * along_w, along_px) ||
        !project(middle_w + kDelta_m * out_w, out_px))
      continue;
    glm::dvec2 ends_px[2];
    if (!project(middle_w - half_length_m * along_w, ends_px[0]) ||
        !project(middle_w + half_length_m * along_w, ends_px[1]) || !inFrame(ends_px[0]) || !inFrame(ends_px[1]))
      continue;
    ++sides_in_view;
    // Pixels of the image across the edge per metre of the tag's plane.
    const glm::dvec2 edge_direction = glm::normalize(along_px - middle_px);
    const glm::dvec2 out_step = out_px - middle_px;
    const double px_per_m = std::abs(edge_direction.x * out_step.y - edge_direction.y * out_step.x) / kDelta_m;
    const double reach_px = std::min(settings.max_reach_px, 0.45 * cell_m * px_per_m);
    if (!(reach_px >= settings.min_reach_px)) {
      ++sides_too_small;
      continue;
    }
    const double reach_m = reach_px / px_per_m;
    // The pixels whose centres can lie within reach of the side's middle part.
    glm::dvec2 low(1e300), high(-1e300);
    for (double along_sign : {-1.0, 1.0})
      for (double out_sign : {-1.0, 1.0}) {
        glm::dvec2 corner;
        if (!project(middle_w + along_sign * half_length_m * along_w + out_sign * reach_m * out_w, corner)) continue;
        low = glm::min(low, corner);
        high = glm::max(high, corner);
      }
    const int x0 = std::max(0, static_cast<int>(std::floor(low.x))), x1 = std::min(camera.width_px - 1, static_cast<int>(std::ceil(high.x)));
    const int y0 = std::max(0, static_cast<int>(std::floor(low.y))), y1 = std::min(camera.height_px - 1, static_cast<int>(std::ceil(high.y)));
    std::vector<Sample> samples;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const glm::dvec3 ray_w = world_from_cam * pixelToCameraRay(camera, glm::dvec2(x, y));
        if (!(ray_w.z < -1e-9) || !std::isfinite(ray_w.z)) continue;
        const glm::dvec3 hit = eye_w + (-eye_w.z / ray_w.z) * ray_w;
        const glm::dvec2 from_middle = glm::dvec2(hit) - middle_w;
        if (std::abs(glm::dot(from_middle, along_w)) > half_length_m) continue;
        const double across_m = glm::dot(from_middle, out_w);
        if (std::abs(across_m) > reach_m) continue;
        const glm::u8vec3 rgb = read_pixel(x, y);
        double linear = 0.0;
        for (int c = 0; c < 3; ++c) linear += decodeCameraValue(settings.camera_transfer, rgb[c] / 255.0);
        samples.push_back({across_m * px_per_m, linear / 3.0});
      }
    // The levels' first guess: the outer 40% of the reach on either side.
    std::vector<double> inside, outside;
    for (const Sample& sample : samples) {
      if (sample.across_px <= -0.6 * reach_px) inside.push_back(sample.linear);
      if (sample.across_px >= 0.6 * reach_px) outside.push_back(sample.linear);
    }
    if (static_cast<int>(samples.size()) < settings.min_samples_per_side || inside.size() < 4 || outside.size() < 4) {
      ++sides_too_small;
      continue;
    }
    const SideFit fit = fitBlurredStep(samples, reach_px, median(inside), median(outside));
    if (!fit.converged || !(std::abs(fit.outside_level - fit.inside_level) >= settings.min_step) ||
        !(fit.rms_residual_of_step <= settings.max_rms_residual) ||
        !(std::abs(fit.offset_px) + fit.sigma_px < reach_px)) {
      ++sides_without_edge;
      continue;
    }
    pooled_variance += fit.sigma_px * fit.sigma_px;
    reading.samples += static_cast<long>(samples.size());
    ++reading.sides;
  }
  if (reading.sides == 0) {
    reading.status = sides_in_view == 0        ? EdgeBlurStatus::kNotInView
                     : sides_too_small > 0     ? EdgeBlurStatus::kTooSmall
                                               : EdgeBlurStatus::kNoEdge;
    reading.message = sides_in_view == 0 ? "no side of the tag is wholly in the frame"
                      : "of the tag's " + std::to_string(sides_in_view) + " sides in view, " +
                            std::to_string(sides_too_small) + " too small in the image and " +
                            std::to_string(sides_without_edge) + " without a clean edge";
    return reading;
  }
  reading.status = EdgeBlurStatus::kMeasured;
  reading.edge_sigma_px = std::sqrt(pooled_variance / reading.sides);
  reading.lens_sigma_px =
      std::sqrt(std::max(reading.edge_sigma_px * reading.edge_sigma_px - kPixelAreaVariancePx2, 0.0));
  reading.ten_to_ninety_px = kTenToNinetyPerSigma * reading.edge_sigma_px;
  return reading;
}

}  // namespace probelight::ibl
