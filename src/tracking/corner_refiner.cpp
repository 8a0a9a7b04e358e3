#include "tracking/corner_refiner.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "ibl/camera_projection.hpp"
#include "tracking/robust_line_fit.hpp"

namespace probelight::tracking {

namespace {

// sRGB code -> linear light. The simulator encodes sRGB, and so do the UVC and
// libcamera pipelines the kiosk uses by default; for another transfer the
// decode is approximate but still monotonic, so edges stay found.
const std::array<double, 256>& srgbToLinearTable() {
  static const std::array<double, 256> table = [] {
    std::array<double, 256> t{};
    for (int i = 0; i < 256; ++i) {
      double c = i / 255.0;
      t[static_cast<std::size_t>(i)] = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    }
    return t;
  }();
  return table;
}

class LinearImage {
 public:
  LinearImage(const std::uint8_t* luma, int width, int height, int stride)
      : luma_(luma), width_(width), height_(height), stride_(stride), lut_(srgbToLinearTable()) {}
  // Whether bilinear samples at p need no pixel outside the frame, with a
  // margin for the rounding of points stepped between two inside ones.
  bool inside(glm::dvec2 p) const {
    constexpr double kMarginPx = 1e-6;
    return p.x >= kMarginPx && p.y >= kMarginPx && p.x < width_ - 1 - kMarginPx && p.y < height_ - 1 - kMarginPx;
  }
  // Bilinear in linear light (decode first, then interpolate: the average of
  // the codes is not the code of the average); p must be inside().
  double sampleInside(glm::dvec2 p) const {
    const int x = static_cast<int>(p.x), y = static_cast<int>(p.y);  // floor: p >= 0
    const double ax = p.x - x, ay = p.y - y;
    const std::uint8_t* row0 = luma_ + static_cast<std::ptrdiff_t>(y) * stride_ + x;
    const std::uint8_t* row1 = row0 + stride_;
    const double top = lut_[row0[0]] + ax * (lut_[row0[1]] - lut_[row0[0]]);
    const double bottom = lut_[row1[0]] + ax * (lut_[row1[1]] - lut_[row1[0]]);
    return top + ay * (bottom - top);
  }

 private:
  const std::uint8_t* luma_;
  int width_, height_, stride_;
  const std::array<double, 256>& lut_;
};

// Lens model both ways, in pixels: undistorted points stay in pixels (the
// pinhole's K applied to the undistorted ray). ibl/camera_projection's
// formulas, which tests check against OpenCV's projectPoints and
// undistortPoints; called per point, without OpenCV's per-call set-up (a
// few hundred calls a frame here).
struct Lens {
  const CameraIntrinsics& camera;
  // Into `out` (cleared), so that loops reuse its storage.
  void undistort(const std::vector<cv::Point2d>& distorted_px, std::vector<cv::Point2d>& out) const {
    out.clear();
    for (const cv::Point2d& p : distorted_px) {
      const glm::dvec3 ray = ibl::pixelToCameraRay(camera, {p.x, p.y});
      out.emplace_back(camera.fx_px * ray.x + camera.cx_px, camera.fy_px * ray.y + camera.cy_px);
    }
  }
  void distort(const std::vector<cv::Point2d>& undistorted_px, std::vector<cv::Point2d>& out) const {
    out.clear();
    for (const cv::Point2d& p : undistorted_px) {
      const glm::dvec2 pixel = ibl::projectToPixel(
          camera, {(p.x - camera.cx_px) / camera.fx_px, (p.y - camera.cy_px) / camera.fy_px, 1.0});
      out.emplace_back(pixel.x, pixel.y);
    }
  }
  std::vector<cv::Point2d> undistort(const std::vector<cv::Point2d>& distorted_px) const {
    std::vector<cv::Point2d> out;
    undistort(distorted_px, out);
    return out;
  }
  std::vector<cv::Point2d> distort(const std::vector<cv::Point2d>& undistorted_px) const {
    std::vector<cv::Point2d> out;
    distort(undistorted_px, out);
    return out;
  }
};

glm::dvec2 toGlm(const cv::Point2d& p) { return {p.x, p.y}; }
cv::Point2d toCv(const glm::dvec2& p) { return {p.x, p.y}; }

// One profile across the edge, from inside (-R) to outside (+R) along the
// outward normal, in linear light, kept as what the area rule needs: its
// trapezoid-rule integral and its plateau levels (the means of its outer
// quarters). Empty when the window leaves the frame.
struct EdgeProfile {
  glm::dvec2 centre{0.0}, outward{0.0};
  double half_width_px = 0.0, step_px = 0.0;
  int intervals = 0;          // samples - 1
  double trapezoid_sum = 0.0;  // sum over intervals of the mean of their two ends
  double inside = 0.0, outside = 0.0;
};

std::optional<EdgeProfile> sampleProfile(const LinearImage& image, glm::dvec2 centre, glm::dvec2 outward,
                                         double half_width_px) {
  // 4 samples a pixel: the trapezoid rule then follows the bilinear
  // interpolant's kinks closely (the area rule needs the integral, not the shape).
  constexpr double kStepPx = 0.25;
  const int n = static_cast<int>(std::ceil(half_width_px / kStepPx));
  EdgeProfile profile{centre, outward, half_width_px, half_width_px / n, 2 * n};
  const glm::dvec2 first = centre - half_width_px * outward, step = profile.step_px * outward;
  // A straight window in a rectangle: inside at both ends is inside throughout.
  if (!image.inside(first) || !image.inside(centre + half_width_px * outward)) return std::nullopt;
  const int ends = std::max(1, n / 4);
  const int last = 2 * n;
  // Three runs (the inner quarter, the middle, the outer quarter) instead of
  // a test per sample: the same sums in the same order.
  double sum = 0.0;
  auto sample = [&](int i) { return image.sampleInside(first + static_cast<double>(i) * step); };
  const double first_value = sample(0);
  sum += first_value;
  profile.inside += first_value;
  int i = 1;
  for (; i < ends; ++i) {
    const double value = sample(i);
    sum += value;
    profile.inside += value;
  }
  for (; i <= last - ends; ++i) sum += sample(i);
  double value = 0.0;
  for (; i <= last; ++i) {
    value = sample(i);
    sum += value;
    profile.outside += value;
  }
  const double end_values = first_value + value;  // value: the last sample's (ends >= 1 keeps it in this run)
  profile.trapezoid_sum = sum - 0.5 * end_values;
  profile.inside /= ends;
  profile.outside /= ends;
  return profile;
}

// Offset (px, along the outward normal) of the step's edge from the profile's
// centre by the area rule of the header, with plateau levels `inside` and
// `outside`; empty when the step has too little contrast to trust.
std::optional<double> edgeOffset(const EdgeProfile& profile, double inside, double outside) {
  double contrast = outside - inside;
  // Either polarity (reversed-border families have white inside the quad's
  // edge); a weak step (shadow, glare, occluder) would give a position
  // dominated by noise, so it is dropped.
  if (!(std::abs(contrast) > 0.02) || !(std::abs(contrast) > 0.2 * std::max(outside, inside))) return std::nullopt;
  // The integral of (value - inside) / contrast over the window.
  const double area = profile.step_px * (profile.trapezoid_sum - profile.intervals * inside) / contrast;
  // Area = distance from the edge to the outer end: edge at R - area from the centre.
  double offset = profile.half_width_px - area;
  if (!(std::abs(offset) < profile.half_width_px)) return std::nullopt;
  return offset;
}

// Homogeneous line a x + b y + c = 0 through points by total least squares,
// Huber-weighted so a few bad samples (a speck, the post's shadow) do not pull it.
std::optional<cv::Vec3d> fitLine(const std::vector<cv::Point2d>& points) {
  if (points.size() < 4) return std::nullopt;
  std::vector<glm::dvec2> as_glm;
  as_glm.reserve(points.size());
  for (const cv::Point2d& p : points) as_glm.emplace_back(p.x, p.y);
  const std::optional<glm::dvec3> line = fitLineRobust(as_glm);
  if (!line) return std::nullopt;
  return cv::Vec3d((*line)[0], (*line)[1], (*line)[2]);
}

}  // namespace

std::optional<RefinedTagCorners> refineTagCorners(const std::uint8_t* luma, int width, int height, int stride_bytes,
                                                  const std::array<glm::dvec2, 4>& corners_px,
                                                  const CameraIntrinsics& camera, int border_width_cells,
                                                  const CornerRefineSettings& settings) {
  if (!luma || width < 4 || height < 4 || stride_bytes < width || border_width_cells < 3) return std::nullopt;
  try {
    const Lens lens{camera};
    LinearImage image(luma, width, height, stride_bytes);
    std::vector<cv::Point2d> corners_cv;
    for (const glm::dvec2& c : corners_px) corners_cv.push_back(toCv(c));
    std::vector<cv::Point2d> corners_u = lens.undistort(corners_cv);  // undistorted pixels

    std::array<double, 4> edge_contrast{};  // outside - inside of each outer edge, last pass
    std::array<std::vector<cv::Point2d>, 4> outer_points_u;  // the last pass's edge points, undistorted
    double outward_sign = 1.0;
    // Scratch for the edges and segments below, reused (cleared) by each.
    std::vector<cv::Point2d> centres_u, probes_u, centres_d, probes_d, edge_d, found_u;
    std::vector<double> half_widths;
    std::vector<EdgeProfile> profiles;
    for (int pass = 0; pass < std::max(1, settings.passes); ++pass) {
      // Orientation: the quad's signed area tells which side of each edge is
      // outside, whatever the winding in the image.
      double signed_area = 0.0;
      for (std::size_t k = 0; k < 4; ++k) signed_area += corners_u[k].cross(corners_u[(k + 1) % 4]);
      if (!(std::abs(signed_area) > 16.0)) return std::nullopt;
      // Positive area: the interior lies left of each edge, so outward is (dy, -dx).
      outward_sign = signed_area > 0 ? 1.0 : -1.0;

      std::array<cv::Vec3d, 4> lines;
      for (std::size_t k = 0; k < 4; ++k) {
        glm::dvec2 a = toGlm(corners_u[k]), b = toGlm(corners_u[(k + 1) % 4]);
        glm::dvec2 opposite_a = toGlm(corners_u[(k + 3) % 4]), opposite_b = toGlm(corners_u[(k + 2) % 4]);
        double length = glm::length(b - a);
        if (!(length > 8.0)) return std::nullopt;
        glm::dvec2 along = (b - a) / length;
        glm::dvec2 outward = outward_sign * glm::dvec2(along.y, -along.x);
        // Half the window: half a border cell, so the window holds only the
        // black border inside and the white margin (one cell) outside. The
        // cell is measured along the normal at each end of the edge (the
        // view's perspective shrinks it toward the far side).
        auto cellAcross = [&](double t) {
          glm::dvec2 on_edge = a + t * (b - a);
          glm::dvec2 across = (opposite_a + t * (opposite_b - opposite_a)) - on_edge;
          return std::abs(glm::dot(across, outward)) / border_width_cells;
        };
        // Samples: one per pixel along the edge (each adds independent noise
        // and a new sub-pixel phase), up to 256, kept from the corners by a
        // window and a pixel and a half so the other edge never enters it.
        int count = std::clamp(static_cast<int>(length), 8, 256);
        centres_u.clear();
        probes_u.clear();
        half_widths.clear();
        for (int i = 0; i < count; ++i) {
          double t = (i + 0.5) / count;
          double half_width = std::min(0.5 * cellAcross(t), 4.0);
          double keep_off = (half_width + 1.5) / length;
          if (half_width < 1.0 || t < keep_off || t > 1.0 - keep_off) continue;
          glm::dvec2 centre = a + t * (b - a);
          centres_u.push_back(toCv(centre));
          probes_u.push_back(toCv(centre + outward));  // 1 px outward: gives the normal's direction in the frame
          half_widths.push_back(half_width);
        }
        lens.distort(centres_u, centres_d);
        lens.distort(probes_u, probes_d);
        profiles.clear();
        for (std::size_t i = 0; i < centres_d.size(); ++i) {
          glm::dvec2 centre = toGlm(centres_d[i]);
          glm::dvec2 normal = toGlm(probes_d[i]) - centre;
          double scale = glm::length(normal);
          if (!(scale > 0.1)) continue;
          normal /= scale;
          if (auto profile = sampleProfile(image, centre, normal, half_widths[i] * scale)) profiles.push_back(std::move(*profile));
        }
        // Plateau levels averaged over neighbouring profiles along the edge:
        // the area rule multiplies a level's error by the window's width, so
        // a single profile's few end samples would carry most of its noise.
        // The tag's black and white vary slowly along an edge (lighting), so
        // a +-kNeighbours window keeps them local.
        constexpr int kNeighbours = 4;
        edge_d.clear();
        double contrast_sum = 0.0;
        for (const EdgeProfile& profile : profiles) contrast_sum += profile.outside - profile.inside;
        edge_contrast[k] = profiles.empty() ? 0.0 : contrast_sum / static_cast<double>(profiles.size());
        for (std::size_t i = 0; i < profiles.size(); ++i) {
          std::size_t first = i >= kNeighbours ? i - kNeighbours : 0;
          std::size_t last = std::min(profiles.size() - 1, i + kNeighbours);
          double inside = 0.0, outside = 0.0;
          for (std::size_t j = first; j <= last; ++j) {
            inside += profiles[j].inside;
            outside += profiles[j].outside;
          }
          inside /= static_cast<double>(last - first + 1);
          outside /= static_cast<double>(last - first + 1);
          if (auto offset = edgeOffset(profiles[i], inside, outside))
            edge_d.push_back(toCv(profiles[i].centre + *offset * profiles[i].outward));
        }
        // Fewer than half the samples usable: the edge is occluded or washed out.
        if (edge_d.size() < std::max<std::size_t>(4, centres_d.size() / 2)) return std::nullopt;
        outer_points_u[k] = lens.undistort(edge_d);
        std::optional<cv::Vec3d> line = fitLine(outer_points_u[k]);
        if (!line) return std::nullopt;
        lines[k] = *line;
      }
      // Corner k lies on edge k-1 (corner k-1 -> k) and edge k (k -> k+1).
      std::vector<cv::Point2d> refined_u;
      for (std::size_t k = 0; k < 4; ++k) {
        cv::Vec3d x = lines[(k + 3) % 4].cross(lines[k]);
        if (!(std::abs(x[2]) > 1e-12)) return std::nullopt;
        refined_u.emplace_back(x[0] / x[2], x[1] / x[2]);
      }
      corners_u = refined_u;
    }
    std::vector<cv::Point2d> refined_d = lens.distort(corners_u);
    RefinedTagCorners refined;
    for (std::size_t k = 0; k < 4; ++k) {
      refined.corners_px[k] = toGlm(refined_d[k]);
      if (!std::isfinite(refined.corners_px[k].x) || !std::isfinite(refined.corners_px[k].y) ||
          !(glm::length(refined.corners_px[k] - corners_px[k]) <= settings.max_shift_px))
        return std::nullopt;
    }

    // Every cell boundary of the tag's grid (the border's inner edge and the
    // bit cells'), found without knowing the code: a boundary between cells
    // of different colour is a step at least half as strong as the outer
    // edge's, one between equal cells has none and is skipped. Each step is
    // at a known place on the tag, so it constrains the pose as the outer
    // edges do, from other positions and at other sub-pixel phases, which
    // averages out the edge errors that are constant along one straight edge
    // (sampling of an edge nearly parallel to the pixel grid).
    const std::array<cv::Point2f, 4> unit{cv::Point2f(-1, -1), cv::Point2f(1, -1), cv::Point2f(1, 1), cv::Point2f(-1, 1)};
    std::array<cv::Point2f, 4> quad;
    for (std::size_t k = 0; k < 4; ++k) quad[k] = cv::Point2f(static_cast<float>(corners_u[k].x), static_cast<float>(corners_u[k].y));
    cv::Matx33d H = cv::getPerspectiveTransform(unit.data(), quad.data());
    auto map = [&](glm::dvec2 q) {
      cv::Vec3d h = H * cv::Vec3d(q.x, q.y, 1.0);
      return glm::dvec2(h[0] / h[2], h[1] / h[2]);
    };
    double outer_contrast = 0.0;
    for (double c : edge_contrast) outer_contrast += std::abs(c) / 4.0;
    const int cells = border_width_cells;
    const double cell = 2.0 / cells;  // in unit tag coordinates
    for (int direction = 0; direction < 2; ++direction) {
      for (int j = 1; j < cells; ++j) {
        for (int m = 0; m < cells; ++m) {
          // Segment from qa to qb along one grid line, between cell m's ends.
          double line = -1.0 + j * cell, from = -1.0 + m * cell, to = from + cell;
          glm::dvec2 qa = direction == 0 ? glm::dvec2(line, from) : glm::dvec2(from, line);
          glm::dvec2 qb = direction == 0 ? glm::dvec2(line, to) : glm::dvec2(to, line);
          glm::dvec2 across_q = direction == 0 ? glm::dvec2(cell, 0.0) : glm::dvec2(0.0, cell);
          glm::dvec2 a = map(qa), b = map(qb);
          double length = glm::length(b - a);
          if (!(length > 4.0)) continue;
          glm::dvec2 along = (b - a) / length;
          glm::dvec2 normal(along.y, -along.x);
          glm::dvec2 mid_q = 0.5 * (qa + qb);
          double cell_across = std::min(std::abs(glm::dot(map(mid_q + across_q) - map(mid_q), normal)),
                                        std::abs(glm::dot(map(mid_q - across_q) - map(mid_q), normal)));
          // Half a cell each side, at most 3 px (the anti-aliasing ramp is
          // about +-1 px); a pixel and a half from the ends plus half the
          // window keeps the cells beyond the ends out of the profiles.
          double half_width = std::min(0.5 * cell_across, 3.0);
          double keep_off = 1.5 + 0.5 * half_width;
          if (half_width < 1.0 || length < 2.0 * keep_off + 1.0) continue;
          int count = std::max(1, static_cast<int>(length - 2.0 * keep_off));
          centres_u.clear();
          probes_u.clear();
          for (int i = 0; i < count; ++i) {
            double d = keep_off + (i + 0.5) * (length - 2.0 * keep_off) / count;
            glm::dvec2 centre = a + d * along;
            centres_u.push_back(toCv(centre));
            probes_u.push_back(toCv(centre + normal));
          }
          lens.distort(centres_u, centres_d);
          lens.distort(probes_u, probes_d);
          profiles.clear();
          for (std::size_t i = 0; i < centres_d.size(); ++i) {
            glm::dvec2 centre = toGlm(centres_d[i]);
            glm::dvec2 n = toGlm(probes_d[i]) - centre;
            double scale = glm::length(n);
            if (!(scale > 0.1)) continue;
            if (auto profile = sampleProfile(image, centre, n / scale, half_width * scale)) profiles.push_back(std::move(*profile));
          }
          if (profiles.empty()) continue;
          // Both sides of one segment are single cells: one pair of levels.
          double inside = 0.0, outside = 0.0;
          for (const EdgeProfile& profile : profiles) {
            inside += profile.inside / profiles.size();
            outside += profile.outside / profiles.size();
          }
          if (!(std::abs(outside - inside) > 0.5 * outer_contrast)) continue;
          edge_d.clear();
          for (const EdgeProfile& profile : profiles)
            if (auto offset = edgeOffset(profile, inside, outside)) edge_d.push_back(toCv(profile.centre + *offset * profile.outward));
          lens.undistort(edge_d, found_u);
          for (const cv::Point2d& p : found_u) refined.edge_points.push_back({toGlm(p), qa, qb});
        }
      }
    }
    for (std::size_t k = 0; k < 4; ++k)
      for (const cv::Point2d& p : outer_points_u[k])
        refined.edge_points.push_back({toGlm(p), glm::dvec2(unit[k].x, unit[k].y),
                                       glm::dvec2(unit[(k + 1) % 4].x, unit[(k + 1) % 4].y)});
    return refined;
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
}

}  // namespace probelight::tracking
