#include "ibl/sensor_noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "ibl/camera_projection.hpp"

namespace probelight::ibl {

namespace {

// The rounding of a value to an integer code adds a uniform error of
// variance 1/12 code^2.
constexpr double kRoundingVarianceCode2 = 1.0 / 12.0;

struct CellFit {
  glm::dvec3 mean{0.0};
  glm::dvec3 residual_sum{0.0};  // of squares, about each channel's plane
  long pixels = 0;
  double dof() const { return static_cast<double>(pixels - 3); }
  double meanVariance() const { return (residual_sum.x + residual_sum.y + residual_sum.z) / (3.0 * dof()); }
  double luma() const { return 0.2126 * mean.x + 0.7152 * mean.y + 0.0722 * mean.z; }
};

// a, b, c, d: a convex quad's corners in order; whether p is inside it
// (either winding).
bool insideQuad(const std::array<glm::dvec2, 4>& quad, const glm::dvec2& p) {
  int positive = 0, negative = 0;
  for (int i = 0; i < 4; ++i) {
    const glm::dvec2 edge = quad[(i + 1) % 4] - quad[i], to_p = p - quad[i];
    const double cross = edge.x * to_p.y - edge.y * to_p.x;
    if (cross > 0.0) ++positive;
    if (cross < 0.0) ++negative;
  }
  return positive == 0 || negative == 0;
}

// Least-squares plane v = a + b dx + c dy per channel over the pixels; the
// residual sum of squares. Positions relative to their mean keep the
// normal equations well conditioned.
CellFit fitCell(const std::vector<glm::dvec2>& positions, const std::vector<glm::dvec3>& values) {
  CellFit fit;
  fit.pixels = static_cast<long>(positions.size());
  glm::dvec2 centre(0.0);
  for (size_t i = 0; i < positions.size(); ++i) {
    centre += positions[i];
    fit.mean += values[i];
  }
  centre /= static_cast<double>(fit.pixels);
  fit.mean /= static_cast<double>(fit.pixels);
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  glm::dvec3 sxv(0.0), syv(0.0);
  for (size_t i = 0; i < positions.size(); ++i) {
    const glm::dvec2 d = positions[i] - centre;
    const glm::dvec3 v = values[i] - fit.mean;
    sxx += d.x * d.x;
    sxy += d.x * d.y;
    syy += d.y * d.y;
    sxv += d.x * v;
    syv += d.y * v;
  }
  const double det = sxx * syy - sxy * sxy;
  glm::dvec3 slope_x(0.0), slope_y(0.0);
  if (det > 1e-9 * (sxx * syy + 1e-30)) {
    slope_x = (syy * sxv - sxy * syv) / det;
    slope_y = (sxx * syv - sxy * sxv) / det;
  }
  for (size_t i = 0; i < positions.size(); ++i) {
    const glm::dvec2 d = positions[i] - centre;
    const glm::dvec3 r = values[i] - fit.mean - d.x * slope_x - d.y * slope_y;
    fit.residual_sum += r * r;
  }
  return fit;
}

// Pools a level's cells, leaving out those whose residual is far above the
// level's median (not flat). Returns the cells left out.
int poolLevel(std::vector<CellFit> cells, double outlier_ratio, NoiseAtLevel& level) {
  if (cells.empty()) return 0;
  std::vector<double> variances;
  for (const CellFit& cell : cells) variances.push_back(cell.meanVariance());
  std::nth_element(variances.begin(), variances.begin() + variances.size() / 2, variances.end());
  const double median = variances[variances.size() / 2];
  glm::dvec3 residual(0.0), mean(0.0);
  double dof = 0.0;
  int left_out = 0;
  for (const CellFit& cell : cells) {
    if (cell.meanVariance() > outlier_ratio * median && cell.meanVariance() > kRoundingVarianceCode2) {
      ++left_out;
      continue;
    }
    residual += cell.residual_sum;
    mean += cell.mean * static_cast<double>(cell.pixels);
    dof += cell.dof();
    level.pixels += cell.pixels;
    ++level.cells;
  }
  if (level.pixels > 0) {
    level.mean_code = mean / static_cast<double>(level.pixels);
    level.sigma_code = glm::sqrt(residual / dof);
  }
  return left_out;
}

}  // namespace

TagCellGrid tagCellGrid(int width_at_border_cells, int total_width_cells, double tag_size_m) {
  if (width_at_border_cells <= 0 || total_width_cells < width_at_border_cells || !(tag_size_m > 0.0)) return {};
  return {total_width_cells, tag_size_m / width_at_border_cells};
}

const char* toString(SensorNoiseStatus status) {
  switch (status) {
    case SensorNoiseStatus::kMeasured: return "measured";
    case SensorNoiseStatus::kNotInView: return "not_in_view";
    case SensorNoiseStatus::kTooSmall: return "too_small";
    case SensorNoiseStatus::kNotFlat: return "not_flat";
  }
  return "unknown";
}

SensorNoiseReading measureSensorNoise(const CameraIntrinsics& camera, const PoseCamFromWorld& pose,
                                      const TagCellGrid& grid, const RgbPixelReader& read_pixel,
                                      const SensorNoiseSettings& settings) {
  SensorNoiseReading reading;
  auto toPixel = [&](double x_w, double y_w, glm::dvec2& pixel) {
    const glm::dvec3 point_cam = pose.toCamera(glm::dvec3(x_w, y_w, 0.0));
    if (!(point_cam.z > 1e-6)) return false;
    pixel = projectToPixel(camera, point_cam);
    return std::isfinite(pixel.x) && std::isfinite(pixel.y);
  };
  if (grid.grid_cells <= 0 || !(grid.cell_m > 0.0)) {
    reading.message = "no tag grid to measure the noise on";
    return reading;
  }
  std::vector<CellFit> fits;
  int too_small = 0, clipped = 0;
  std::vector<glm::dvec2> positions;
  std::vector<glm::dvec3> values;
  const double half_grid_m = grid.grid_cells * grid.cell_m / 2.0;
  for (int row = 0; row < grid.grid_cells; ++row)
    for (int col = 0; col < grid.grid_cells; ++col) {
      const double x0 = -half_grid_m + col * grid.cell_m, y0 = -half_grid_m + row * grid.cell_m;
      const double x1 = x0 + grid.cell_m, y1 = y0 + grid.cell_m;
      // The cell's scale in the image: its shorter projected side.
      std::array<glm::dvec2, 4> cell_px;
      if (!toPixel(x0, y0, cell_px[0]) || !toPixel(x1, y0, cell_px[1]) || !toPixel(x1, y1, cell_px[2]) ||
          !toPixel(x0, y1, cell_px[3]))
        continue;
      bool in_frame = true;
      for (const glm::dvec2& p : cell_px)
        if (p.x < -0.5 || p.y < -0.5 || p.x > camera.width_px - 0.5 || p.y > camera.height_px - 0.5) in_frame = false;
      if (!in_frame) continue;
      ++reading.cells_in_view;
      double side_px = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 4; ++i) side_px = std::min(side_px, glm::length(cell_px[(i + 1) % 4] - cell_px[i]));
      const double margin_m = settings.edge_clearance_px * grid.cell_m / side_px;
      if (!(2.0 * margin_m < grid.cell_m)) {
        ++too_small;
        continue;
      }
      std::array<glm::dvec2, 4> inner;
      if (!toPixel(x0 + margin_m, y0 + margin_m, inner[0]) || !toPixel(x1 - margin_m, y0 + margin_m, inner[1]) ||
          !toPixel(x1 - margin_m, y1 - margin_m, inner[2]) || !toPixel(x0 + margin_m, y1 - margin_m, inner[3]))
        continue;
      glm::dvec2 low(inner[0]), high(inner[0]);
      for (const glm::dvec2& p : inner) {
        low = glm::min(low, p);
        high = glm::max(high, p);
      }
      positions.clear();
      values.clear();
      bool cut_off = false;
      // Pixel centres at integers (OpenCV's convention, projectToPixel's).
      for (int y = static_cast<int>(std::ceil(low.y)); y <= static_cast<int>(std::floor(high.y)); ++y)
        for (int x = static_cast<int>(std::ceil(low.x)); x <= static_cast<int>(std::floor(high.x)); ++x) {
          if (x < 0 || y < 0 || x >= camera.width_px || y >= camera.height_px) continue;
          if (!insideQuad(inner, glm::dvec2(x, y))) continue;
          const glm::u8vec3 rgb = read_pixel(x, y);
          for (int c = 0; c < 3; ++c)
            if (rgb[c] >= settings.clip_code || rgb[c] <= settings.floor_code) cut_off = true;
          positions.emplace_back(x, y);
          values.emplace_back(rgb.r, rgb.g, rgb.b);
        }
      if (cut_off) {
        ++clipped;
        continue;
      }
      if (static_cast<int>(positions.size()) < std::max(settings.min_pixels_per_cell, 4)) {
        ++too_small;
        continue;
      }
      fits.push_back(fitCell(positions, values));
    }
  reading.cells_left_out = too_small + clipped;
  if (reading.cells_in_view == 0) {
    reading.message = "the tag's cells are not in the frame";
    return reading;
  }
  if (fits.size() < 2 * static_cast<size_t>(settings.min_cells_per_level)) {
    reading.status = SensorNoiseStatus::kTooSmall;
    reading.message = std::to_string(fits.size()) + " of the tag's " + std::to_string(reading.cells_in_view) +
                      " cells in view have a flat interior to measure (" + std::to_string(too_small) +
                      " too small in the image, " + std::to_string(clipped) + " clipped or black)";
    return reading;
  }
  // The two inks: split halfway between the darkest and brightest cells.
  double darkest = fits.front().luma(), brightest = darkest;
  for (const CellFit& fit : fits) {
    darkest = std::min(darkest, fit.luma());
    brightest = std::max(brightest, fit.luma());
  }
  const double split = 0.5 * (darkest + brightest);
  std::vector<CellFit> dark, bright;
  for (const CellFit& fit : fits) (fit.luma() < split ? dark : bright).push_back(fit);
  reading.cells_left_out += poolLevel(dark, settings.outlier_variance_ratio, reading.dark);
  reading.cells_left_out += poolLevel(bright, settings.outlier_variance_ratio, reading.bright);
  if (reading.dark.cells < settings.min_cells_per_level || reading.bright.cells < settings.min_cells_per_level ||
      // Two inks tell apart by far more than the noise; a tag seen through
      // fog, or a grey card, does not show two levels.
      !(brightest - darkest > 8.0 * std::max(reading.dark.sigma_code.y, reading.bright.sigma_code.y))) {
    reading.status = SensorNoiseStatus::kNotFlat;
    reading.message = "the tag's cells do not show two flat inks (" + std::to_string(reading.dark.cells) +
                      " dark and " + std::to_string(reading.bright.cells) + " bright cells kept)";
    return reading;
  }
  reading.status = SensorNoiseStatus::kMeasured;
  return reading;
}

AddedNoiseModel addedNoiseModel(const NoiseAtLevel& dark, const NoiseAtLevel& bright) {
  AddedNoiseModel model;
  model.dark_code = dark.mean_code;
  model.bright_code = bright.mean_code;
  auto added = [](const glm::dvec3& sigma) {
    return glm::sqrt(glm::max(sigma * sigma - glm::dvec3(kRoundingVarianceCode2), glm::dvec3(0.0)));
  };
  model.dark_sigma_code = added(dark.sigma_code);
  model.bright_sigma_code = added(bright.sigma_code);
  return model;
}

glm::dvec3 addedNoiseSigmaCode(const AddedNoiseModel& model, const glm::dvec3& code) {
  glm::dvec3 sigma;
  for (int c = 0; c < 3; ++c) {
    const double span = model.bright_code[c] - model.dark_code[c];
    const double t = span > 0.0 ? std::clamp((code[c] - model.dark_code[c]) / span, 0.0, 1.0) : 0.0;
    sigma[c] = model.dark_sigma_code[c] + t * (model.bright_sigma_code[c] - model.dark_sigma_code[c]);
  }
  return sigma;
}

}  // namespace probelight::ibl
