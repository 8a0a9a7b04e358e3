#include "tracking/probe_edge_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace probelight::tracking {

namespace {

// Bilinear sample of the linear-light table at (x, y); false outside the frame.
bool sampleLinear(const std::uint8_t* luma, int width, int height, int stride, const std::array<double, 256>& to_linear,
                  double x, double y, double& value) {
  if (!(x >= 0.0 && y >= 0.0 && x <= width - 1.0 && y <= height - 1.0)) return false;
  const int x0 = std::min(static_cast<int>(x), width - 2), y0 = std::min(static_cast<int>(y), height - 2);
  const double fx = x - x0, fy = y - y0;
  const std::uint8_t* row0 = luma + static_cast<std::ptrdiff_t>(y0) * stride + x0;
  const std::uint8_t* row1 = row0 + stride;
  value = (1 - fy) * ((1 - fx) * to_linear[row0[0]] + fx * to_linear[row0[1]]) +
          fy * ((1 - fx) * to_linear[row1[0]] + fx * to_linear[row1[1]]);
  return true;
}

struct EdgeObservation {
  glm::dvec2 point_px;   // on the predicted outline
  glm::dvec2 normal;     // outward
  double offset_px;      // where the edge is along the normal
};

}  // namespace

ProbeEdgeFit fitProbeOutlineToEdges(const std::uint8_t* luma, int width, int height, int stride_bytes,
                                    const ibl::ProbeOutline& outline, double probe_reflectance,
                                    const ibl::CameraTransfer& transfer, const ProbeEdgeFitSettings& settings) {
  ProbeEdgeFit fit;
  const std::size_t n = outline.polygon_px.size();
  if (!luma || width < 2 || height < 2 || stride_bytes < width) {
    fit.reason = "no frame";
    return fit;
  }
  if (!outline.valid || n < 8 || !(outline.radius_px > 0.0)) {
    fit.reason = "no predicted outline";
    return fit;
  }
  if (settings.samples < 8 || !(settings.search_px > 0.0) || !(probe_reflectance > 0.0 && probe_reflectance < 1.0)) {
    fit.reason = probe_reflectance >= 1.0 ? "a ball of reflectance 1 has no silhouette to fit" : "bad settings";
    return fit;
  }
  std::array<double, 256> to_linear{};
  for (int code = 0; code < 256; ++code) to_linear[static_cast<std::size_t>(code)] = ibl::decodeCameraValue(transfer, code / 255.0);

  // Profiles at 1/4 px steps, interpolated between: the crossing of a
  // bilinear edge is then found to a few hundredths of a pixel.
  constexpr double kStepPx = 0.25;
  const int half_steps = static_cast<int>(std::ceil(settings.search_px / kStepPx));
  std::vector<EdgeObservation> edges;
  for (int i = 0; i < settings.samples; ++i) {
    // Point and outward normal on the polygon, at an even share of its vertices.
    const std::size_t k = static_cast<std::size_t>(i) * n / static_cast<std::size_t>(settings.samples);
    const glm::dvec2 p = outline.polygon_px[k];
    const glm::dvec2 tangent = outline.polygon_px[(k + 1) % n] - outline.polygon_px[(k + n - 1) % n];
    if (!(glm::length(tangent) > 0.0)) continue;
    glm::dvec2 normal = glm::normalize(glm::dvec2(tangent.y, -tangent.x));
    if (glm::dot(normal, p - outline.center_px) < 0.0) normal = -normal;
    ++fit.profiles;
    std::vector<double> profile;
    profile.reserve(static_cast<std::size_t>(2 * half_steps + 1));
    bool inside_frame = true;
    for (int s = -half_steps; s <= half_steps && inside_frame; ++s) {
      double value = 0.0;
      const glm::dvec2 q = p + (s * kStepPx) * normal;
      inside_frame = sampleLinear(luma, width, height, stride_bytes, to_linear, q.x, q.y, value);
      profile.push_back(value);
    }
    if (!inside_frame) continue;
    // From the outside in: the background's level, the outermost pixel's
    // worth of the profile; the silhouette is where the light first falls
    // to halfway between that and the ball's rim (reflectance times the
    // same background), found by linear interpolation between samples.
    const int ends = std::max(1, static_cast<int>(1.0 / kStepPx));
    double background = 0.0;
    for (int e = 0; e < ends; ++e) background += profile[profile.size() - 1 - static_cast<std::size_t>(e)] / ends;
    const double step = (1.0 - probe_reflectance) * background;
    if (!(background > 0.0) || !(step >= settings.min_relative_step * background)) continue;
    const double threshold = background - 0.5 * step;
    double crossing_px = 0.0;  // the crossing, px along the normal
    bool crossed = false;
    std::size_t crossing_index = 0;
    for (std::size_t s = profile.size() - 1; s-- > 0;) {
      if (profile[s] < threshold) {
        const double t = (profile[s + 1] - threshold) / (profile[s + 1] - profile[s]);  // 0 at s + 1, 1 at s
        crossing_px = (static_cast<double>(s + 1) - t - half_steps) * kStepPx;
        crossing_index = s + 1;
        crossed = true;
        break;
      }
    }
    // Outside the ball, beyond the edge's own blur (a pixel and a half), the
    // background must be about level: a quarter of the step is the most it
    // may vary (texture, a tag edge behind, shading would bias the crossing).
    bool flat_outside = crossed;
    const std::size_t blur_samples = static_cast<std::size_t>(1.5 / kStepPx);
    for (std::size_t s = crossing_index + blur_samples; crossed && s < profile.size(); ++s)
      if (std::abs(profile[s] - background) > 0.25 * step) flat_outside = false;
    if (!crossed || !flat_outside) continue;
    edges.push_back({p, normal, crossing_px});
  }
  fit.trusted_profiles = static_cast<int>(edges.size());
  if (fit.trusted_profiles < std::max(3.0, settings.min_trusted_fraction * settings.samples)) {
    fit.reason = "too few clear edge profiles (" + std::to_string(fit.trusted_profiles) + " of " +
                 std::to_string(fit.profiles) + ")";
    return fit;
  }

  // offset_i = n_i . d + (s - 1) n_i . (p_i - c): linear in (d.x, d.y, s - 1).
  // Huber weights at half a pixel against profiles caught by texture.
  constexpr double kHuberPx = 0.5;
  glm::dvec3 solution(0.0);
  std::vector<double> weights(edges.size(), 1.0);
  for (int iteration = 0; iteration < 4; ++iteration) {
    glm::dmat3 normal_matrix(0.0);
    glm::dvec3 rhs(0.0);
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const EdgeObservation& e = edges[i];
      const glm::dvec3 row(e.normal.x, e.normal.y, glm::dot(e.normal, e.point_px - outline.center_px));
      normal_matrix += weights[i] * glm::outerProduct(row, row);
      rhs += weights[i] * e.offset_px * row;
    }
    if (!(std::abs(glm::determinant(normal_matrix)) > 1e-12)) {
      fit.reason = "edges do not constrain the outline";
      return fit;
    }
    solution = glm::inverse(normal_matrix) * rhs;
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const EdgeObservation& e = edges[i];
      const double residual = e.offset_px - (glm::dot(e.normal, glm::dvec2(solution.x, solution.y)) +
                                             solution.z * glm::dot(e.normal, e.point_px - outline.center_px));
      weights[i] = std::abs(residual) <= kHuberPx ? 1.0 : kHuberPx / std::abs(residual);
    }
  }
  double squared_sum = 0.0, weight_sum = 0.0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const EdgeObservation& e = edges[i];
    const double residual = e.offset_px - (glm::dot(e.normal, glm::dvec2(solution.x, solution.y)) +
                                           solution.z * glm::dot(e.normal, e.point_px - outline.center_px));
    squared_sum += weights[i] * residual * residual;
    weight_sum += weights[i];
  }
  fit.shift_px = glm::dvec2(solution.x, solution.y);
  fit.radius_scale = 1.0 + solution.z;
  fit.center_px = outline.center_px + fit.shift_px;
  fit.radius_px = outline.radius_px * fit.radius_scale;
  fit.rms_px = std::sqrt(squared_sum / weight_sum);
  if (!std::isfinite(fit.rms_px) || !(fit.rms_px <= settings.max_rms_px)) {
    fit.reason = "edges scatter too much about any outline (rms " + std::to_string(fit.rms_px) + " px)";
    return fit;
  }
  if (!(glm::length(fit.shift_px) <= settings.search_px) ||
      !(std::abs(solution.z) * outline.radius_px <= settings.search_px)) {
    fit.reason = "the fitted outline moved beyond the search range";
    return fit;
  }
  fit.ok = true;
  return fit;
}

glm::dvec3 probeCenterForImageShift(const PoseCamFromWorld& pose, const CameraIntrinsics& camera,
                                    const glm::dvec3& probe_center_w, const glm::dvec2& shift_px) {
  const glm::dvec3 center_cam = pose.toCamera(probe_center_w);
  if (!(center_cam.z > 0.0)) return probe_center_w;
  const glm::dvec3 moved_cam =
      center_cam + glm::dvec3(shift_px.x * center_cam.z / camera.fx_px, shift_px.y * center_cam.z / camera.fy_px, 0.0);
  return glm::transpose(pose.R_cam_from_world) * (moved_cam - pose.t_cam_from_world);
}

}  // namespace probelight::tracking
