#include "ibl/light_dome.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "core/finite_vector.hpp"
#include "core/math_constants.hpp"
#include "ibl/color_transfer.hpp"

namespace probelight::ibl {

namespace {

glm::dvec3 directionAt(double azimuth_rad, double elevation_rad) {
  return {std::cos(elevation_rad) * std::cos(azimuth_rad), std::cos(elevation_rad) * std::sin(azimuth_rad),
          std::sin(elevation_rad)};
}

// The upper hemisphere as a grid of cells of equal azimuth and elevation
// extent, each with its radiance, solid angle and exact first moment
// integral of w dw (so that a cell of constant radiance contributes exactly).
struct HemisphereGrid {
  int width = 0, height = 0;  // azimuth cells, elevation cells (row 0 at the horizon)
  std::vector<glm::dvec3> radiance;
  std::vector<double> solid_angle;
  std::vector<glm::dvec3> moment;
  std::vector<std::uint8_t> clipped;
  double cell_azimuth_rad = 0.0, cell_elevation_rad = 0.0;

  std::size_t index(int column, int row) const { return static_cast<std::size_t>(row) * width + column; }
  double azimuthAt(double column) const { return column * cell_azimuth_rad; }
  double elevationAt(double row) const { return row * cell_elevation_rad; }
};

HemisphereGrid resample(const CubeMapRGB& cube, const std::vector<float>* validity, const LightDomeSettings& settings,
                        double clip_level) {
  HemisphereGrid grid;
  grid.width = std::max(4, settings.azimuth_cells);
  grid.height = std::max(2, settings.elevation_cells);
  grid.cell_azimuth_rad = 2.0 * kPi / grid.width;
  grid.cell_elevation_rad = 0.5 * kPi / grid.height;
  const std::size_t cells = static_cast<std::size_t>(grid.width) * grid.height;
  grid.radiance.assign(cells, glm::dvec3(0.0));
  grid.solid_angle.assign(cells, 0.0);
  grid.moment.assign(cells, glm::dvec3(0.0));
  grid.clipped.assign(cells, 0);
  std::vector<std::uint8_t> seen(cells, 1);
  const int n = cube.face_size;
  const bool has_validity =
      validity && n > 0 && validity->size() == static_cast<std::size_t>(kCubeFaceCount) * n * n;
  auto sample = [&](const glm::dvec3& dir, bool& valid, bool& clipped) {
    valid = true;
    clipped = false;
    if (n <= 0) return glm::dvec3(0.0);
    const CubeTexelCoord coord = directionToCubeCoord(dir);
    const int x = std::clamp(static_cast<int>(coord.s * n), 0, n - 1);
    const int y = std::clamp(static_cast<int>(coord.t * n), 0, n - 1);
    if (has_validity) valid = (*validity)[static_cast<std::size_t>(coord.face) * n * n + y * n + x] >= 0.5f;
    const glm::vec3 nearest = cube.texel(coord.face, x, y);
    if (clip_level > 0.0 && allFinite(nearest))
      clipped = std::max({nearest.r, nearest.g, nearest.b}) >= 0.98 * clip_level;
    const glm::vec3 value = cube.sampleBilinear(dir);
    return allFinite(value) ? glm::max(glm::dvec3(value), glm::dvec3(0.0)) : glm::dvec3(0.0);
  };
  glm::dvec3 valid_sum(0.0);
  double valid_weight = 0.0;
  for (int row = 0; row < grid.height; ++row) {
    const double e0 = grid.elevationAt(row), e1 = grid.elevationAt(row + 1);
    // Exact per-cell integrals: dw = cos(e) de da, w = (cos e cos a, cos e sin a, sin e).
    const double solid = (std::sin(e1) - std::sin(e0)) * grid.cell_azimuth_rad;
    const double cos2 = 0.5 * (e1 - e0) + 0.25 * (std::sin(2 * e1) - std::sin(2 * e0));  // integral of cos^2 e
    const double sincos = 0.5 * (std::sin(e1) * std::sin(e1) - std::sin(e0) * std::sin(e0));
    for (int column = 0; column < grid.width; ++column) {
      const double a0 = grid.azimuthAt(column), a1 = grid.azimuthAt(column + 1);
      const std::size_t i = grid.index(column, row);
      grid.solid_angle[i] = solid;
      grid.moment[i] = {cos2 * (std::sin(a1) - std::sin(a0)), cos2 * (std::cos(a0) - std::cos(a1)),
                        sincos * grid.cell_azimuth_rad};
      glm::dvec3 sum(0.0);
      int valid_count = 0, clipped_count = 0;
      for (int sy = 0; sy < 2; ++sy)
        for (int sx = 0; sx < 2; ++sx) {
          bool valid = true, clipped = false;
          const glm::dvec3 value =
              sample(directionAt(grid.azimuthAt(column + 0.25 + 0.5 * sx), grid.elevationAt(row + 0.25 + 0.5 * sy)),
                     valid, clipped);
          if (valid) {
            sum += value;
            ++valid_count;
          }
          clipped_count += clipped ? 1 : 0;
        }
      if (valid_count >= 2) {
        grid.radiance[i] = sum / static_cast<double>(valid_count);
        valid_sum += grid.radiance[i] * solid;
        valid_weight += solid;
      } else {
        seen[i] = 0;
      }
      grid.clipped[i] = clipped_count >= 2 ? 1 : 0;
    }
  }
  const glm::dvec3 fill = valid_weight > 0.0 ? valid_sum / valid_weight : glm::dvec3(0.0);
  for (std::size_t i = 0; i < cells; ++i)
    if (!seen[i]) grid.radiance[i] = fill;
  return grid;
}

// A rectangle of cells [column0, column1) x [row0, row1).
struct Region {
  int column0 = 0, column1 = 0, row0 = 0, row1 = 0;
};

std::vector<std::size_t> cellsOf(const HemisphereGrid& grid, const Region& region) {
  std::vector<std::size_t> cells;
  for (int row = region.row0; row < region.row1; ++row)
    for (int column = region.column0; column < region.column1; ++column) cells.push_back(grid.index(column, row));
  return cells;
}

glm::dvec3 cellCentre(const HemisphereGrid& grid, std::size_t i) {
  return directionAt(grid.azimuthAt(static_cast<double>(i % grid.width) + 0.5),
                     grid.elevationAt(static_cast<double>(i / grid.width) + 0.5));
}

// The light for a set of cells (its region): first moments, and the angle
// from the light within which half the region's energy lies, which is what
// sets how soft its shadow looks (a lamp with a little sky around it casts
// the lamp's sharp shadow, not one blurred by the sky's share).
DomeLight lightOf(const HemisphereGrid& grid, const std::vector<std::size_t>& cells) {
  glm::dvec3 moment_r(0.0), moment_g(0.0), moment_b(0.0), moment_y(0.0), centre(0.0);
  double energy_y = 0.0, solid = 0.0;
  for (std::size_t i : cells) {
    const glm::dvec3& L = grid.radiance[i];
    moment_r += L.r * grid.moment[i];
    moment_g += L.g * grid.moment[i];
    moment_b += L.b * grid.moment[i];
    moment_y += luminance(L) * grid.moment[i];
    energy_y += luminance(L) * grid.solid_angle[i];
    solid += grid.solid_angle[i];
    centre += grid.moment[i];
  }
  DomeLight light;
  light.solid_angle_sr = solid;
  const double length = glm::length(moment_y);
  if (length > 0.0 && std::isfinite(length)) {
    light.direction_w = moment_y / length;
  } else if (glm::length(centre) > 0.0) {
    light.direction_w = glm::normalize(centre);  // no light in the region: its geometric centre, no colour
  }
  if (light.direction_w.z < 0.0) light.direction_w = glm::normalize(glm::dvec3(light.direction_w.x, light.direction_w.y, 0.0));
  light.rgb = glm::max(glm::dvec3(glm::dot(moment_r, light.direction_w), glm::dot(moment_g, light.direction_w),
                                  glm::dot(moment_b, light.direction_w)),
                       glm::dvec3(0.0));
  if (energy_y > 0.0) {
    std::vector<std::pair<double, double>> by_angle;  // (angle, energy)
    by_angle.reserve(cells.size());
    for (std::size_t i : cells)
      by_angle.emplace_back(std::acos(std::clamp(glm::dot(cellCentre(grid, i), light.direction_w), -1.0, 1.0)),
                            luminance(grid.radiance[i]) * grid.solid_angle[i]);
    std::sort(by_angle.begin(), by_angle.end());
    double running = 0.0;
    for (const auto& [angle, energy] : by_angle) {
      running += energy;
      if (running >= 0.5 * energy_y) {
        light.spread_rad = angle;
        break;
      }
    }
  }
  return light;
}

double regionEnergy(const HemisphereGrid& grid, const Region& region) {
  double energy = 0.0;
  for (int row = region.row0; row < region.row1; ++row)
    for (int column = region.column0; column < region.column1; ++column) {
      const std::size_t i = grid.index(column, row);
      energy += luminance(grid.radiance[i]) * grid.solid_angle[i];
    }
  return energy;
}

// Splits at the energy median along the region's longer side (as arcs:
// azimuth extent times cos of the middle elevation). A region one cell
// across in that direction is split along the other; a single cell is not
// split (returns false).
bool splitAtMedian(const HemisphereGrid& grid, const Region& region, Region& first, Region& second) {
  const int columns = region.column1 - region.column0, rows = region.row1 - region.row0;
  if (columns * rows < 2) return false;
  const double middle_elevation = grid.elevationAt(0.5 * (region.row0 + region.row1));
  const double azimuth_arc = columns * grid.cell_azimuth_rad * std::cos(middle_elevation);
  const double elevation_arc = rows * grid.cell_elevation_rad;
  const bool along_azimuth = rows < 2 || (columns >= 2 && azimuth_arc >= elevation_arc);
  const int count = along_azimuth ? columns : rows;
  std::vector<double> slice(static_cast<std::size_t>(count), 0.0);
  for (int row = region.row0; row < region.row1; ++row)
    for (int column = region.column0; column < region.column1; ++column) {
      const std::size_t i = grid.index(column, row);
      slice[static_cast<std::size_t>(along_azimuth ? column - region.column0 : row - region.row0)] +=
          luminance(grid.radiance[i]) * grid.solid_angle[i];
    }
  double total = 0.0;
  for (double e : slice) total += e;
  // The cut after which the running energy first reaches half (in the
  // middle when the region is dark), keeping both sides non-empty.
  int cut = count / 2;
  if (total > 0.0) {
    double running = 0.0;
    for (int k = 0; k < count; ++k) {
      running += slice[static_cast<std::size_t>(k)];
      if (running >= 0.5 * total) {
        // Whichever boundary, before or after this slice, is nearer the median.
        cut = running - 0.5 * total < 0.5 * slice[static_cast<std::size_t>(k)] ? k + 1 : k;
        break;
      }
    }
  }
  cut = std::clamp(cut, 1, count - 1);
  first = second = region;
  if (along_azimuth) {
    first.column1 = region.column0 + cut;
    second.column0 = region.column0 + cut;
  } else {
    first.row1 = region.row0 + cut;
    second.row0 = region.row0 + cut;
  }
  return true;
}

std::vector<Region> fixedRegions(const HemisphereGrid& grid, int count);

std::vector<Region> medianCutRegions(const HemisphereGrid& grid, int count) {
  std::vector<Region> regions{{0, grid.width, 0, grid.height}};
  // Debevec's median cut splits every region at each level; for a count
  // that is not a power of two the last level splits the regions with the
  // most energy first.
  while (static_cast<int>(regions.size()) < count) {
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t i = 0; i < regions.size(); ++i) order.emplace_back(regionEnergy(grid, regions[i]), i);
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    const int splits = std::min(static_cast<int>(regions.size()), count - static_cast<int>(regions.size()));
    std::vector<Region> next;
    std::vector<bool> split_this(regions.size(), false);
    for (int k = 0; k < splits; ++k) split_this[order[static_cast<std::size_t>(k)].second] = true;
    bool any = false;
    for (std::size_t i = 0; i < regions.size(); ++i) {
      Region a, b;
      if (split_this[i] && splitAtMedian(grid, regions[i], a, b)) {
        next.push_back(a);
        next.push_back(b);
        any = true;
      } else {
        next.push_back(regions[i]);
      }
    }
    regions = std::move(next);
    if (!any) break;  // every region is a single cell
  }
  return regions;
}

// Energy-weighted k-means on the sphere (Lloyd's iterations), started from
// the median cut: each cell goes to the light nearest its direction, each
// light moves to its cells' first moment. This lowers the energy-weighted
// angular spread of the lights, the blur of their shadows, so a small bright
// lamp ends with a light at its centre and a region that is mostly lamp.
std::vector<std::vector<std::size_t>> clusteredRegions(const HemisphereGrid& grid, const std::vector<Region>& start) {
  std::vector<glm::dvec3> centres;
  for (const Region& region : start) centres.push_back(lightOf(grid, cellsOf(grid, region)).direction_w);
  const std::size_t cells = grid.radiance.size();
  std::vector<std::vector<std::size_t>> members(centres.size());
  constexpr int kIterations = 12;
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    for (auto& m : members) m.clear();
    for (std::size_t i = 0; i < cells; ++i) {
      const glm::dvec3 d = cellCentre(grid, i);
      std::size_t nearest = 0;
      double best = -2.0;
      for (std::size_t k = 0; k < centres.size(); ++k) {
        const double c = glm::dot(d, centres[k]);
        if (c > best) {
          best = c;
          nearest = k;
        }
      }
      members[nearest].push_back(i);
    }
    bool moved = false;
    for (std::size_t k = 0; k < centres.size(); ++k) {
      if (members[k].empty()) continue;
      const glm::dvec3 next = lightOf(grid, members[k]).direction_w;
      moved = moved || glm::dot(next, centres[k]) < std::cos(1e-4);
      centres[k] = next;
    }
    if (!moved) break;
  }
  return members;
}

// Equal solid angles: a zenith cap of 2 pi / N and N - 1 azimuth sectors
// below it (N <= 4: N sectors over the whole hemisphere). Rows are cut at the
// cell nearest the exact elevation, columns at the nearest cell boundary.
std::vector<Region> fixedRegions(const HemisphereGrid& grid, int count) {
  std::vector<Region> regions;
  auto sectors = [&](int sector_count, int row0, int row1) {
    for (int k = 0; k < sector_count; ++k) {
      const int c0 = static_cast<int>(std::lround(static_cast<double>(k) * grid.width / sector_count));
      const int c1 = static_cast<int>(std::lround(static_cast<double>(k + 1) * grid.width / sector_count));
      if (c1 > c0 && row1 > row0) regions.push_back({c0, c1, row0, row1});
    }
  };
  if (count <= 4) {
    sectors(count, 0, grid.height);
    return regions;
  }
  // Cap area 2 pi (1 - sin e_c) = 2 pi / N.
  const double cap_elevation = std::asin(1.0 - 1.0 / count);
  const int cap_row = std::clamp(static_cast<int>(std::lround(cap_elevation / grid.cell_elevation_rad)), 1,
                                 grid.height - 1);
  sectors(count - 1, 0, cap_row);
  regions.push_back({0, grid.width, cap_row, grid.height});
  return regions;
}

// The largest relative error, over 48 normals with z >= 0.5 (a Fibonacci
// spiral over that cap), of the lights' irradiance against the grid's exact
// upper-hemisphere irradiance (per-cell moments); 0 where the grid is dark.
double worstUpperIrradianceError(const HemisphereGrid& grid, const std::vector<DomeLight>& lights) {
  constexpr int kNormals = 48;
  double worst = 0.0;
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < kNormals; ++k) {
    const double z = 1.0 - 0.5 * (k + 0.5) / kNormals;  // uniform in area over z in [0.5, 1]
    const double ring = std::sqrt(1.0 - z * z);
    const glm::dvec3 n(ring * std::cos(golden_angle * k), ring * std::sin(golden_angle * k), z);
    double truth = 0.0;
    for (std::size_t i = 0; i < grid.radiance.size(); ++i)
      truth += luminance(grid.radiance[i]) * std::max(0.0, glm::dot(n, grid.moment[i]));
    double dome = 0.0;
    for (const DomeLight& light : lights) dome += luminance(light.rgb) * std::max(0.0, glm::dot(n, light.direction_w));
    if (truth > 0.0) worst = std::max(worst, std::abs(dome - truth) / truth);
  }
  return worst;
}

}  // namespace

const char* toString(DomePlacement placement) {
  switch (placement) {
    case DomePlacement::kFixedRegions: return "fixed";
    case DomePlacement::kMedianCut: return "median_cut";
    case DomePlacement::kClustered: return "clustered";
  }
  return "unknown";
}

std::vector<DomeLight> fitLightDome(const CubeMapRGB& radiance, const std::vector<float>* validity,
                                    const LightDomeSettings& settings) {
  std::vector<DomeLight> lights;
  if (settings.light_count < 1) return lights;
  const HemisphereGrid grid = resample(radiance, validity, settings, 0.0);
  if (settings.placement == DomePlacement::kClustered) {
    // k-means finds a local optimum that depends on where it starts; start
    // from both the median cut and the fixed regions and keep the dome that
    // best reproduces the upper hemisphere's irradiance, the dome's job, at
    // the worst of a set of normals with z >= 0.5 (exact per-cell integrals
    // of the grid are the reference).
    double best_worst = std::numeric_limits<double>::infinity();
    for (const std::vector<Region>& start :
         {medianCutRegions(grid, settings.light_count), fixedRegions(grid, settings.light_count)}) {
      std::vector<DomeLight> candidate;
      for (const std::vector<std::size_t>& cells : clusteredRegions(grid, start))
        if (!cells.empty()) candidate.push_back(lightOf(grid, cells));
      const double worst = worstUpperIrradianceError(grid, candidate);
      if (lights.empty() || worst < best_worst) {
        best_worst = worst;
        lights = std::move(candidate);
      }
    }
    return lights;
  }
  const std::vector<Region> regions = settings.placement == DomePlacement::kFixedRegions
                                          ? fixedRegions(grid, settings.light_count)
                                          : medianCutRegions(grid, settings.light_count);
  for (const Region& region : regions) lights.push_back(lightOf(grid, cellsOf(grid, region)));
  return lights;
}

glm::dvec3 domeIrradiance(const std::vector<DomeLight>& lights, const glm::dvec3& normal) {
  glm::dvec3 sum(0.0);
  for (const DomeLight& light : lights) sum += light.rgb * std::max(0.0, glm::dot(normal, light.direction_w));
  return sum;
}

namespace {

// 4-connected regions of the cells where `mask` is set, wrapping in azimuth.
std::vector<std::vector<std::size_t>> connectedBlobs(const HemisphereGrid& grid, const std::vector<std::uint8_t>& mask) {
  const std::size_t cells = mask.size();
  std::vector<int> label(cells, -1);
  std::vector<std::vector<std::size_t>> blobs;
  for (std::size_t start = 0; start < cells; ++start) {
    if (!mask[start] || label[start] >= 0) continue;
    const int id = static_cast<int>(blobs.size());
    blobs.emplace_back();
    std::queue<std::size_t> open;
    open.push(start);
    label[start] = id;
    while (!open.empty()) {
      const std::size_t i = open.front();
      open.pop();
      blobs.back().push_back(i);
      const int column = static_cast<int>(i % grid.width), row = static_cast<int>(i / grid.width);
      const int neighbours[4][2] = {{(column + 1) % grid.width, row},
                                    {(column + grid.width - 1) % grid.width, row},
                                    {column, row + 1},
                                    {column, row - 1}};
      for (const auto& [c, r] : neighbours) {
        if (r < 0 || r >= grid.height) continue;
        const std::size_t j = grid.index(c, r);
        if (mask[j] && label[j] < 0) {
          label[j] = id;
          open.push(j);
        }
      }
    }
  }
  return blobs;
}

}  // namespace

DominantLight findDominantLight(const CubeMapRGB& radiance, const std::vector<float>* validity,
                                const std::vector<DomeLight>& lights, double clip_level,
                                const LightDomeSettings& settings) {
  DominantLight dominant;
  if (lights.empty()) return dominant;
  const HemisphereGrid grid = resample(radiance, validity, settings, clip_level);

  std::vector<std::vector<std::size_t>> blobs = connectedBlobs(grid, grid.clipped);
  const std::size_t cells = grid.clipped.size();
  double best_solid = 0.0;
  int best = -1;
  for (std::size_t b = 0; b < blobs.size(); ++b) {
    double solid = 0.0;
    for (std::size_t i : blobs[b]) solid += grid.solid_angle[i];
    if (solid > best_solid) {
      best_solid = solid;
      best = static_cast<int>(b);
    }
  }
  if (best >= 0) {
    glm::dvec3 sum(0.0);
    for (std::size_t i : blobs[static_cast<std::size_t>(best)]) sum += grid.moment[i];  // integral of w dw
    if (glm::length(sum) > 0.0) {
      dominant.found = true;
      dominant.from_clipped_region = true;
      dominant.clipped_solid_angle_sr = best_solid;
      dominant.direction_w = glm::normalize(sum);
    }
  }
  if (!dominant.found) {
    // No clipping: the source is the region at least half as bright as the
    // brightest cell, 4-connected; of several, the one carrying the most
    // power; its direction the luminance-weighted centre. A sun is a few
    // cells, a soft box its whole face, whose brightest cell alone could sit
    // anywhere on it.
    double peak = 0.0;
    for (std::size_t i = 0; i < cells; ++i) peak = std::max(peak, luminance(grid.radiance[i]));
    std::vector<std::uint8_t> bright(cells, 0);
    for (std::size_t i = 0; i < cells; ++i) bright[i] = peak > 0.0 && luminance(grid.radiance[i]) >= 0.5 * peak;
    double best_power = 0.0;
    for (const std::vector<std::size_t>& blob : connectedBlobs(grid, bright)) {
      double power = 0.0;
      glm::dvec3 centre(0.0);
      for (std::size_t i : blob) {
        power += luminance(grid.radiance[i]) * grid.solid_angle[i];
        centre += luminance(grid.radiance[i]) * grid.moment[i];
      }
      if (power > best_power && glm::length(centre) > 0.0) {
        best_power = power;
        dominant.direction_w = glm::normalize(centre);
        dominant.found = true;
      }
    }
  }
  if (dominant.found) {
    const auto nearest = std::max_element(lights.begin(), lights.end(), [&](const DomeLight& a, const DomeLight& b) {
      return glm::dot(a.direction_w, dominant.direction_w) < glm::dot(b.direction_w, dominant.direction_w);
    });
    dominant.rgb = nearest->rgb;
  }
  return dominant;
}

}  // namespace probelight::ibl
