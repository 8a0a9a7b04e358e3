#include "sim/world.hpp"

#include <algorithm>
#include <atomic>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <thread>
#include <unordered_map>

#include <opencv2/calib3d.hpp>

#include "core/math_constants.hpp"
#include "sim/camera_path.hpp"
#include "sim/environment.hpp"
#include "sim/gltf_brdf.hpp"
#include "sim/occluder.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/tag_pattern.hpp"

namespace probelight::sim {
namespace {

constexpr double kAutoExposureWhiteAlbedo = 0.85;
constexpr double kAutoExposureTargetLinear = 0.5;
constexpr int kPostAzimuthSteps = 32;

// Brute-force integration grid: cells of equal (theta, phi) extent, each with
// its exact cosine moment m = integral of omega d(omega) over the cell, so
// that integral of L max(0, n.omega) = sum L_cell max(0, n.m_cell) is exact for
// cell-constant L wherever a cell lies wholly on one side of n's horizon.
constexpr int kGridWidth = 512;
constexpr int kGridHeight = 256;
constexpr int kGridSubsamples = 3;

double luminance(const glm::dvec3& rgb) { return 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b; }

std::uint64_t splitMix64(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

glm::dvec3 rotateZ(const glm::dvec3& v, double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {c * v.x - s * v.y, s * v.x + c * v.y, v.z};
}

// Acklam's rational approximation of the standard normal quantile (relative
// error < 1.2e-9), enough for a noise table.
double normalQuantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01,  -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  const double low = 0.02425;
  if (p < low) {
    double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - low) return -normalQuantile(1 - p);
  double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

// kGaussianTableSize equal-probability standard-normal values: 12 bits of a
// hash pick one. 4096 floats stay in the first-level cache, where a 65536
// table's three random reads a pixel cost an eighth of a frame. The
// quantiles are rescaled to unit variance (4096 quantiles alone have 0.9997:
// their tails stop at 3.7 sigma), so the noise's sigma is the scene's.
constexpr int kGaussianTableBits = 12;
constexpr int kGaussianTableSize = 1 << kGaussianTableBits;
const std::vector<float>& gaussianTable() {
  static const std::vector<float> table = [] {
    std::vector<double> quantiles(kGaussianTableSize);
    double sum_of_squares = 0.0;
    for (int i = 0; i < kGaussianTableSize; ++i) {
      quantiles[i] = normalQuantile((i + 0.5) / kGaussianTableSize);
      sum_of_squares += quantiles[i] * quantiles[i];
    }
    const double unit_variance = 1.0 / std::sqrt(sum_of_squares / kGaussianTableSize);
    std::vector<float> t(kGaussianTableSize);
    for (int i = 0; i < kGaussianTableSize; ++i) t[i] = static_cast<float>(quantiles[i] * unit_variance);
    return t;
  }();
  return table;
}

// sRGB encoding of linear [0,1] to code values [0,255], tabulated with linear
// interpolation (error < 0.002 code values).
class SrgbEncoder {
 public:
  SrgbEncoder() : table_(kSize + 2) {
    for (int i = 0; i <= kSize + 1; ++i) {
      double x = std::min(1.0, static_cast<double>(i) / kSize);
      double encoded = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
      table_[i] = static_cast<float>(encoded * 255.0);
    }
  }
  float encode(double linear) const {
    double x = std::clamp(linear, 0.0, 1.0) * kSize;
    int i = static_cast<int>(x);
    double f = x - i;
    return static_cast<float>(table_[i] + f * (table_[i + 1] - table_[i]));
  }

 private:
  static constexpr int kSize = 8192;
  std::vector<float> table_;
};

template <typename Fn>
void parallelRows(int rows, int threads, Fn fn) {
  // Blocks of rows go to whichever thread is free next, not in a fixed
  // order: rows with the ball cost more, and a thread the scheduler stalls
  // (the kiosk's own pipeline shares the cores) leaves its blocks to the
  // others instead of holding up the frame. Which thread renders a row
  // changes nothing in it.
  constexpr int kBlock = 8;
  if (threads <= 1) {
    fn(0, rows, 1);
    return;
  }
  std::atomic<int> next_start{0};
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([&] {
      for (int start = next_start.fetch_add(kBlock); start < rows; start = next_start.fetch_add(kBlock))
        fn(start, std::min(rows, start + kBlock), 1);
    });
  }
  for (std::thread& w : workers) w.join();
}

struct GridCell {
  glm::dvec3 moment;  // integral of omega over the cell
  double theta0, theta1, phi0, phi1;
};

const std::vector<GridCell>& directionGrid() {
  static const std::vector<GridCell> grid = [] {
    std::vector<GridCell> cells(kGridWidth * kGridHeight);
    for (int row = 0; row < kGridHeight; ++row) {
      double t0 = kPi * row / kGridHeight, t1 = kPi * (row + 1) / kGridHeight;
      // integral of sin^2(theta) and sin(theta)cos(theta) over [t0, t1]
      double sin2 = (t1 - t0) / 2 - (std::sin(2 * t1) - std::sin(2 * t0)) / 4;
      double sincos = (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0)) / 2;
      for (int col = 0; col < kGridWidth; ++col) {
        double p0 = -kPi + 2 * kPi * col / kGridWidth, p1 = -kPi + 2 * kPi * (col + 1) / kGridWidth;
        GridCell& cell = cells[row * kGridWidth + col];
        cell.moment = {(std::sin(p1) - std::sin(p0)) * sin2, (std::cos(p0) - std::cos(p1)) * sin2, (p1 - p0) * sincos};
        cell.theta0 = t0;
        cell.theta1 = t1;
        cell.phi0 = p0;
        cell.phi1 = p1;
      }
    }
    return cells;
  }();
  return grid;
}

// Mean of fn over a cell's sub-samples, weighted by sin(theta) (solid angle).
template <typename Fn>
void cellMean(const GridCell& cell, Fn fn) {
  for (int i = 0; i < kGridSubsamples; ++i) {
    double theta = cell.theta0 + (cell.theta1 - cell.theta0) * (i + 0.5) / kGridSubsamples;
    double weight = std::sin(theta);
    for (int j = 0; j < kGridSubsamples; ++j) {
      double phi = cell.phi0 + (cell.phi1 - cell.phi0) * (j + 0.5) / kGridSubsamples;
      fn(glm::dvec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)), weight);
    }
  }
}

// Radiance per cell of the upper hemisphere only (rows 0..H/2-1).
template <typename Fn>
std::vector<glm::dvec3> upperHemisphereCells(Fn radiance, int threads) {
  const auto& grid = directionGrid();
  std::vector<glm::dvec3> cells(kGridWidth * kGridHeight / 2, glm::dvec3(0.0));
  parallelRows(kGridHeight / 2, threads, [&](int r0, int r1, int) {
    for (int row = r0; row < r1; ++row)
      for (int col = 0; col < kGridWidth; ++col) {
        glm::dvec3 sum(0.0);
        double weight_sum = 0.0;
        cellMean(grid[row * kGridWidth + col], [&](const glm::dvec3& dir, double w) {
          sum += w * radiance(dir);
          weight_sum += w;
        });
        cells[row * kGridWidth + col] = sum / weight_sum;
      }
  });
  return cells;
}

glm::dvec3 integrateCosine(const std::vector<glm::dvec3>& cells, const glm::dvec3& normal) {
  const auto& grid = directionGrid();
  glm::dvec3 sum(0.0);
  for (size_t i = 0; i < cells.size(); ++i) {
    double c = glm::dot(normal, grid[i].moment);
    if (c > 0.0) sum += c * cells[i];
  }
  return sum;
}

// Smooth value noise in [-1, 1] with zero mean: a floor texture with no edges,
// so it never looks like a tag to the detector. Its lattice values are
// hashed from (salt, ix, iy); the ones within kTabulatedCells of the origin
// are hashed once, up front (hashing four per lookup, two lookups per floor
// hit, was nearly half of a frame's time), the rest as they are needed: the
// same function everywhere, bit for bit.
class ValueNoise {
 public:
  static constexpr std::int64_t kTabulatedCells = 128;

  explicit ValueNoise(std::uint64_t salt) : salt_(salt), table_(kSide * kSide) {
    for (std::int64_t iy = -kTabulatedCells; iy <= kTabulatedCells; ++iy)
      for (std::int64_t ix = -kTabulatedCells; ix <= kTabulatedCells; ++ix)
        table_[static_cast<std::size_t>((iy + kTabulatedCells) * kSide + ix + kTabulatedCells)] = hashed(ix, iy);
  }

  double operator()(double x, double y) const {
    // A grazing ray meets the floor out past 1e15 cells: no texture there,
    // and no int64 overflow below.
    if (!(std::abs(x) < 1e15 && std::abs(y) < 1e15)) return 0.0;
    // floor() by truncation: without SSE4.1 std::floor is a long sequence,
    // and this runs twice for every floor ray.
    std::int64_t ix = static_cast<std::int64_t>(x), iy = static_cast<std::int64_t>(y);
    ix -= x < static_cast<double>(ix) ? 1 : 0;
    iy -= y < static_cast<double>(iy) ? 1 : 0;
    double tx = x - static_cast<double>(ix), ty = y - static_cast<double>(iy);
    tx = tx * tx * (3 - 2 * tx);
    ty = ty * ty * (3 - 2 * ty);
    double a, b, c, d;
    if (ix >= -kTabulatedCells && ix < kTabulatedCells && iy >= -kTabulatedCells && iy < kTabulatedCells) {
      const double* row = &table_[static_cast<std::size_t>((iy + kTabulatedCells) * kSide + ix + kTabulatedCells)];
      a = row[0], b = row[1], c = row[kSide], d = row[kSide + 1];
    } else {
      a = lattice(ix, iy), b = lattice(ix + 1, iy), c = lattice(ix, iy + 1), d = lattice(ix + 1, iy + 1);
    }
    return (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty;
  }

 private:
  static constexpr std::int64_t kSide = 2 * kTabulatedCells + 1;

  double hashed(std::int64_t ix, std::int64_t iy) const {
    const std::uint64_t h = splitMix64(salt_ ^ splitMix64(static_cast<std::uint64_t>(ix) * 73856093ull ^
                                                          static_cast<std::uint64_t>(iy) * 19349663ull));
    return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53) * 2.0 - 1.0;
  }
  double lattice(std::int64_t ix, std::int64_t iy) const {
    if (ix < -kTabulatedCells || ix > kTabulatedCells || iy < -kTabulatedCells || iy > kTabulatedCells)
      return hashed(ix, iy);
    return table_[static_cast<std::size_t>((iy + kTabulatedCells) * kSide + ix + kTabulatedCells)];
  }

  std::uint64_t salt_;
  std::vector<double> table_;
};

struct TruthGrid {
  std::vector<glm::dvec3> hdr;      // camera linear units
  std::vector<glm::dvec3> clipped;  // camera linear units, reflectance undone
};

// ---- Shadow truth of virtual occluders ----

// The upper hemisphere is rows 0 .. kUpperRows-1 of the direction grid (row
// kUpperRows starts exactly at the horizon).
constexpr int kUpperRows = kGridHeight / 2;
// A piece of sky cut by an occluder's outline is split kShadowSplit x
// kShadowSplit: level 1 is a cell's own 3x3 sub-samples (as cellMean); a
// level-1 piece still cut is split again while it carries more than
// kShadowRefineShare of E_up, down to level kShadowMaxLevel (1/81 of a cell,
// 0.009 deg). Only the sun and a lamp carry that much per piece, so their
// shadow edges move smoothly with the ground point while the dim sky costs
// one level. Each piece left cut is then decided by its centre, so the error
// of a point is at most the share of its cut sky pieces (~3e-6 of E_up each).
constexpr int kShadowSplit = 3;
constexpr int kShadowMaxLevel = 4;
constexpr double kShadowRefineShare = 1e-5;
// A mesh's outline is not known in closed form, so every piece of sky in
// its bounding cone is decided by rays. Pieces that the sphere and box
// would refine (the sun, a lamp) stop at level 3 (0.027 deg: a sun's shadow
// edge placed to 0.03 mm at 7 cm from the model, far below the 2 mm grid;
// level 2 left 0.0065 of E_up at a sun's penumbra against the analytic box),
// and a cell too dim for any of its level-1 pieces to be refined is
// decided by its centre ray: its error is at most its own share of E_up
// (< 9e-5), of either sign along the outline, so it averages out.
constexpr int kMeshShadowMaxLevel = 3;
// renderWithOccluders: ground grids of exact shadow values, interpolated
// bilinearly. Near an occluder (within 10 cm of its bounding sphere's axis)
// the spacing is 2 mm, about two pixels at the default 0.6 m and under the
// narrowest penumbra there (a 3 deg sun behind a few-cm object: ~2.5 mm).
// Further out, shadows widen in proportion to the distance (a penumbra spans
// >= 0.05 rad of the light as seen from the ground), so the spacing doubles
// with each doubling of the distance: at most 4% of it.
constexpr double kShadowNodeSpacing_m = 0.002;
constexpr double kShadowFineReach_m = 0.10;
constexpr int kShadowCoarsestLevel = 10;
// Beyond this the ground is unshadowed whatever the light (guards the grid
// index against rays that graze the horizon).
constexpr double kShadowFarLimit_m = 1000.0;
// Occluder shading: irradiance by normal at 64 azimuths x 32 polar angles,
// bilinear. Irradiance is a cosine-lobe blur of the sky, smooth except where
// a small sun sets: there the table's error reaches ~2% of the sun's part.
constexpr int kIrradianceTableWidth = 64;
constexpr int kIrradianceTableHeight = 32;

// Where a piece of sky stands relative to one occluder's outline.
enum class Visibility { kClear, kBlocked, kCut };

// The directions from one ground point that hit one occluder.
struct OccluderCone {
  const VirtualOccluder* occluder = nullptr;
  // The bounding sphere's cone: no direction outside it hits the occluder.
  // For a sphere it is exactly the set of directions that hit.
  glm::dvec3 axis{0.0, 0.0, 1.0};
  double half_angle_rad = 0.0, cos_half = 1.0, sin_half = 0.0;
  bool inside_bound = false;       // the point is inside the bounding sphere: no cone
  bool blocks_everything = false;  // the point is inside (or on the bottom of) the occluder
  // Box: inward unit normals of the planes through the point and the box's
  // silhouette edges. The directions from a point to a convex body form a
  // convex cone bounded by exactly those planes, so a direction hits the box
  // iff it is on the inner side of all of them.
  std::array<glm::dvec3, 12> planes{};
  int plane_count = 0;
};

OccluderCone coneFrom(const VirtualOccluder& occluder, const glm::dvec3& point_w) {
  OccluderCone cone;
  cone.occluder = &occluder;
  const OccluderBound bound = occluderBound(occluder);
  const glm::dvec3 to_center = bound.center_w - point_w;
  const double distance_m = glm::length(to_center);
  if (distance_m <= bound.radius_m * (1.0 + 1e-12)) {
    cone.inside_bound = true;
    // A ground point inside a sphere resting on the ground is its contact
    // point, whose whole upper hemisphere the sphere fills.
    if (occluder.shape == VirtualOccluder::Shape::kSphere) cone.blocks_everything = true;
  } else {
    cone.axis = to_center / distance_m;
    cone.sin_half = bound.radius_m / distance_m;
    cone.cos_half = std::sqrt(1.0 - cone.sin_half * cone.sin_half);
    cone.half_angle_rad = std::asin(cone.sin_half);
  }
  // A sphere's cone is exact; a mesh has only its bounding cone.
  if (occluder.shape != VirtualOccluder::Shape::kBox) return cone;

  const glm::dvec3 half_m = 0.5 * occluder.box_size_m;
  const glm::dvec3 q = boxLocalFromWorldDirection(occluder, point_w - boxCenterWorld(occluder));
  // A face "faces" the point when the point is on or outside its plane. On
  // the plane counts as facing, so that a point on the ground under the box
  // (in the bottom face's plane) gets the ground plane as its only bound and
  // a point touching a side face gets that face's plane: both exact.
  auto faces = [&](int axis, double side) { return side * q[axis] >= half_m[axis]; };
  bool any_facing = false;
  for (int axis = 0; axis < 3; ++axis) any_facing = any_facing || faces(axis, -1.0) || faces(axis, 1.0);
  if (!any_facing) {
    cone.blocks_everything = true;
    return cone;
  }
  // Silhouette edges: between a face that faces the point and one that does not.
  for (int along = 0; along < 3; ++along) {
    const int i = (along + 1) % 3, j = (along + 2) % 3;
    for (double si : {-1.0, 1.0})
      for (double sj : {-1.0, 1.0}) {
        if (faces(i, si) == faces(j, sj)) continue;
        glm::dvec3 a(0.0), b(0.0);
        a[i] = b[i] = si * half_m[i];
        a[j] = b[j] = sj * half_m[j];
        a[along] = -half_m[along];
        b[along] = half_m[along];
        glm::dvec3 n = glm::cross(a - q, b - q);
        const double length = glm::length(n);
        if (!(length > 0.0)) continue;
        n /= length;
        if (glm::dot(n, -q) < 0.0) n = -n;  // the box's centre is on the inner side
        cone.planes[static_cast<size_t>(cone.plane_count++)] = boxWorldFromLocalDirection(occluder, n);
      }
  }
  return cone;
}

// Visibility of every direction within rho_rad of dir (unit) from the cone's point.
Visibility classify(const OccluderCone& cone, const glm::dvec3& dir, double rho_rad, double sin_rho, double cos_rho) {
  if (cone.blocks_everything) return Visibility::kBlocked;
  if (!cone.inside_bound) {
    const double c = glm::dot(dir, cone.axis);
    // Angle to the axis > half + rho: the whole patch misses the bounding sphere.
    if (c < cone.cos_half * cos_rho - cone.sin_half * sin_rho) return Visibility::kClear;
    if (cone.occluder->shape == VirtualOccluder::Shape::kSphere) {
      // Angle < half - rho: wholly inside the (exact) cone.
      if (cone.half_angle_rad > rho_rad && c > cone.cos_half * cos_rho + cone.sin_half * sin_rho)
        return Visibility::kBlocked;
      return Visibility::kCut;
    }
  }
  if (cone.occluder->shape != VirtualOccluder::Shape::kBox) return Visibility::kCut;
  if (cone.plane_count == 0) return Visibility::kCut;  // degenerate: let the ray test decide
  // A patch of radius rho around dir is wholly on the inner side of a plane
  // through the point iff n.dir > sin(rho), wholly outside iff n.dir < -sin(rho).
  bool all_inside = true;
  for (int k = 0; k < cone.plane_count; ++k) {
    const double s = glm::dot(cone.planes[static_cast<size_t>(k)], dir);
    if (s < -sin_rho) return Visibility::kClear;
    if (s <= sin_rho) all_inside = false;
  }
  return all_inside ? Visibility::kBlocked : Visibility::kCut;
}

Visibility classifyAll(const std::vector<OccluderCone>& cones, const glm::dvec3& dir, double rho_rad, double sin_rho,
                       double cos_rho) {
  Visibility result = Visibility::kClear;
  for (const OccluderCone& cone : cones) {
    const Visibility v = classify(cone, dir, rho_rad, sin_rho, cos_rho);
    if (v == Visibility::kBlocked) return v;
    if (v == Visibility::kCut) result = v;
  }
  return result;
}

// Whether the ray from point_w along dir hits an occluder. The cone and plane
// tests are exact for a single direction (rho = 0); the ray test settles the
// measure-zero ties on an outline.
bool blockedAlong(const std::vector<OccluderCone>& cones, const glm::dvec3& point_w, const glm::dvec3& dir) {
  for (const OccluderCone& cone : cones) {
    const Visibility v = classify(cone, dir, 0.0, 0.0, 1.0);
    if (v == Visibility::kBlocked) return true;
    if (v == Visibility::kCut && occluderBlocks(*cone.occluder, point_w, dir)) return true;
  }
  return false;
}

// Cells are first tested kColumnBlock at a time (a block's centre and
// radius bound it as a whole), so that the runs wholly blocked or clear cost
// one test and only blocks on an outline are tested cell by cell.
constexpr int kColumnBlock = 16;
constexpr int kBlocksPerRow = kGridWidth / kColumnBlock;

// Per upper-hemisphere cell: its centre direction (the middle of its theta
// and phi ranges), and per row an angular radius rho that bounds the distance
// from the centre to any point of the cell (half the theta extent, then half
// the phi extent along the widest parallel: a path, so an upper bound). The
// same per block of kColumnBlock cells.
struct UpperCellGeometry {
  std::vector<glm::dvec3> centre_dirs;
  std::array<double, kUpperRows> rho_rad{}, sin_rho{}, cos_rho{};
  double max_rho_rad = 0.0;
  std::vector<glm::dvec3> block_dirs;  // kBlocksPerRow per row
  std::array<double, kUpperRows> block_rho_rad{}, block_sin_rho{}, block_cos_rho{};
};

const UpperCellGeometry& upperCellGeometry() {
  static const UpperCellGeometry geometry = [] {
    UpperCellGeometry g;
    const auto& grid = directionGrid();
    g.centre_dirs.resize(static_cast<size_t>(kGridWidth) * kUpperRows);
    for (int row = 0; row < kUpperRows; ++row) {
      const GridCell& first = grid[static_cast<size_t>(row) * kGridWidth];
      const double rho = 0.5 * (first.theta1 - first.theta0) + 0.5 * (first.phi1 - first.phi0) * std::sin(first.theta1);
      g.rho_rad[row] = rho;
      g.sin_rho[row] = std::sin(rho);
      g.cos_rho[row] = std::cos(rho);
      g.max_rho_rad = std::max(g.max_rho_rad, rho);
      const double block_rho = 0.5 * (first.theta1 - first.theta0) +
                               0.5 * kColumnBlock * (first.phi1 - first.phi0) * std::sin(first.theta1);
      g.block_rho_rad[row] = block_rho;
      g.block_sin_rho[row] = std::sin(block_rho);
      g.block_cos_rho[row] = std::cos(block_rho);
      for (int block = 0; block < kBlocksPerRow; ++block) {
        const double theta = 0.5 * (first.theta0 + first.theta1);
        const double phi = -kPi + 2.0 * kPi * (block + 0.5) / kBlocksPerRow;
        g.block_dirs.push_back({std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)});
      }
      for (int col = 0; col < kGridWidth; ++col) {
        const GridCell& cell = grid[static_cast<size_t>(row) * kGridWidth + col];
        const double theta = 0.5 * (cell.theta0 + cell.theta1), phi = 0.5 * (cell.phi0 + cell.phi1);
        g.centre_dirs[static_cast<size_t>(row) * kGridWidth + col] = {std::sin(theta) * std::cos(phi),
                                                                       std::sin(theta) * std::sin(phi), std::cos(theta)};
      }
    }
    return g;
  }();
  return geometry;
}

// A cell's 3x3 level-1 pieces (the same sub-samples as cellMean): centre
// directions per piece (cell-major, then theta, then phi), and per row and
// piece row their exact cosine moment's z and angular radius. Most cut
// pieces are level 1, so these are worth tabulating once.
struct LevelOnePieces {
  std::vector<glm::dvec3> dirs;
  std::array<double, kUpperRows * kShadowSplit> moment_z{}, rho_rad{}, sin_rho{}, cos_rho{};
};

const LevelOnePieces& levelOnePieces() {
  static const LevelOnePieces pieces = [] {
    LevelOnePieces p;
    const auto& grid = directionGrid();
    constexpr int kPerCell = kShadowSplit * kShadowSplit;
    p.dirs.resize(static_cast<size_t>(kGridWidth) * kUpperRows * kPerCell);
    for (int row = 0; row < kUpperRows; ++row) {
      const GridCell& first = grid[static_cast<size_t>(row) * kGridWidth];
      const double dphi = (first.phi1 - first.phi0) / kShadowSplit;
      for (int i = 0; i < kShadowSplit; ++i) {
        const double t0 = first.theta0 + (first.theta1 - first.theta0) * i / kShadowSplit;
        const double t1 = first.theta0 + (first.theta1 - first.theta0) * (i + 1) / kShadowSplit;
        const size_t k = static_cast<size_t>(row) * kShadowSplit + i;
        p.moment_z[k] = dphi * 0.5 * (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0));
        p.rho_rad[k] = 0.5 * (t1 - t0) + 0.5 * dphi * std::sin(t1);
        p.sin_rho[k] = std::sin(p.rho_rad[k]);
        p.cos_rho[k] = std::cos(p.rho_rad[k]);
      }
      for (int col = 0; col < kGridWidth; ++col) {
        const GridCell& cell = grid[static_cast<size_t>(row) * kGridWidth + col];
        for (int i = 0; i < kShadowSplit; ++i)
          for (int j = 0; j < kShadowSplit; ++j) {
            const double theta = cell.theta0 + (cell.theta1 - cell.theta0) * (i + 0.5) / kShadowSplit;
            const double phi = cell.phi0 + (cell.phi1 - cell.phi0) * (j + 0.5) / kShadowSplit;
            p.dirs[(static_cast<size_t>(row) * kGridWidth + col) * kPerCell + i * kShadowSplit + j] = {
                std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
          }
      }
    }
    return p;
  }();
  return pieces;
}

// Camera-linear hdr radiance at every level-1 piece centre of the upper
// hemisphere for one lighting state (float: 7 MB rather than 14).
struct PieceRadiance {
  std::vector<glm::vec3> hdr;
};

// Everything a shadow query needs that does not depend on the ground point.
struct ShadowContext {
  LightingState lighting;
  std::shared_ptr<const TruthGrid> grid;
  std::shared_ptr<const PieceRadiance> pieces;
  glm::dvec3 e_up_hdr{0.0}, e_up_clipped{0.0};  // the grid's upper-hemisphere cosine integral, camera units
  double refine_luminance = 0.0;                 // a cut piece carrying more than this is split again
  std::array<glm::dvec3, kUpperRows> row_max_hdr{};  // per row, the largest cell radiance (for bounds)
  std::vector<VirtualOccluder> occluders;
  int max_level = kShadowMaxLevel;  // kMeshShadowMaxLevel with a mesh among the occluders
  bool meshes_only = false;         // every occluder is a mesh: dim cut cells are decided by their centre
};

// Sums over the pieces of one cut cell, of moment_z * L: over the blocked
// pieces and over all of them, hdr and clipped.
struct PieceSums {
  glm::dvec3 blocked_hdr{0.0}, whole_hdr{0.0}, blocked_clipped{0.0}, whole_clipped{0.0};
};

// renderWithOccluders' per-frame state: the shadow query, the occluders'
// irradiance table, and the ground grid of shadow values filled on demand.
// Directions of the upper hemisphere drawn in proportion to the sky's
// radiance: a cell of the direction grid with probability proportional to
// (its luminance + 1% of the mean) times its solid angle, then a uniform
// direction within it. The floor of 1% keeps every direction possible
// (a sun smaller than the grid's sub-samples is still found, by the BRDF's
// own samples), so the estimate stays unbiased whatever the grid missed.
struct SkySampler {
  std::vector<double> cdf;          // over the kUpperRows x kGridWidth cells, last = 1
  std::vector<double> probability;  // of each cell

  void build(const std::vector<glm::dvec3>& cell_radiance) {
    const auto& grid = directionGrid();
    const size_t cells = static_cast<size_t>(kUpperRows) * kGridWidth;
    double mean = 0.0;
    for (size_t i = 0; i < cells; ++i) mean += luminance(cell_radiance[i]);
    mean /= static_cast<double>(cells);
    probability.resize(cells);
    cdf.resize(cells);
    double total = 0.0;
    for (size_t i = 0; i < cells; ++i) {
      probability[i] = (std::max(0.0, luminance(cell_radiance[i])) + 0.01 * mean + 1e-300) * solidAngle(grid[i]);
      total += probability[i];
    }
    double running = 0.0;
    for (size_t i = 0; i < cells; ++i) {
      probability[i] /= total;
      running += probability[i];
      cdf[i] = running;
    }
    cdf.back() = 1.0;
  }
  static double solidAngle(const GridCell& cell) {
    return (cell.phi1 - cell.phi0) * (std::cos(cell.theta0) - std::cos(cell.theta1));
  }
  // A direction and its density per steradian, from u1, u2, u3 in [0, 1).
  glm::dvec3 sample(double u1, double u2, double u3, double& pdf) const {
    const size_t i = std::min(cdf.size() - 1, static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u1) - cdf.begin()));
    const GridCell& cell = directionGrid()[i];
    const double cos_theta = std::cos(cell.theta0) - u2 * (std::cos(cell.theta0) - std::cos(cell.theta1));
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    const double phi = cell.phi0 + u3 * (cell.phi1 - cell.phi0);
    pdf = probability[i] / solidAngle(cell);
    return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
  }
  double pdf(const glm::dvec3& dir) const {
    if (!(dir.z > 0.0)) return 0.0;
    const size_t i = upperCellOf(dir);
    return probability[i] / solidAngle(directionGrid()[i]);
  }
  // The upper-hemisphere cell holding dir (dir.z > 0).
  static size_t upperCellOf(const glm::dvec3& dir) {
    const double theta = std::acos(std::clamp(dir.z, -1.0, 1.0));
    const double phi = std::atan2(dir.y, dir.x);
    const int row = std::clamp(static_cast<int>(theta / kPi * kGridHeight), 0, kUpperRows - 1);
    const int col = std::clamp(static_cast<int>((phi + kPi) / (2.0 * kPi) * kGridWidth), 0, kGridWidth - 1);
    return static_cast<size_t>(row) * kGridWidth + static_cast<size_t>(col);
  }
};

struct OccluderFrame {
  ShadowContext shadow;
  SkySampler sky_hdr, sky_clipped;  // for meshes' path tracing; built only when a mesh needs them
  // Per upper-hemisphere cell, what the ball's pixel showing it keeps of
  // its light after the camera's clip (1 unclipped; per channel), for a
  // mesh lit by the 8-bit-knowable sky; negative where no ball pixel shows
  // the cell (behind the ball), which keeps the per-direction clip.
  std::vector<glm::dvec3> sky_clip_scale;
  std::vector<glm::dvec3> irradiance_by_normal;  // scene units, kIrradianceTableHeight rows (theta 0..pi) x width (phi)
  mutable std::mutex node_mutex;
  mutable std::unordered_map<std::uint64_t, glm::dvec3> node_fraction;  // hdr fraction by packed grid index

  glm::dvec3 irradiance(const glm::dvec3& normal) const {
    const double theta = std::acos(std::clamp(normal.z, -1.0, 1.0));
    double phi = std::atan2(normal.y, normal.x) / (2.0 * kPi);
    phi -= std::floor(phi);
    const double fy = theta / kPi * (kIrradianceTableHeight - 1), fx = phi * kIrradianceTableWidth;
    const int y0 = std::min(static_cast<int>(fy), kIrradianceTableHeight - 2);
    const int x0 = static_cast<int>(fx) % kIrradianceTableWidth, x1 = (x0 + 1) % kIrradianceTableWidth;
    const double v = fy - y0, u = fx - std::floor(fx);
    auto at = [&](int y, int x) { return irradiance_by_normal[static_cast<size_t>(y) * kIrradianceTableWidth + x]; };
    return (1 - v) * ((1 - u) * at(y0, x0) + u * at(y0, x1)) + v * ((1 - u) * at(y0 + 1, x0) + u * at(y0 + 1, x1));
  }
};

struct FrameState {
  PoseCamFromWorld pose;
  glm::dmat3 world_from_cam;
  glm::dvec3 eye;
  // The ball and its post as every camera ray from `eye` meets them.
  SphereFromOrigin ball_from_eye{glm::dvec3(0.0), glm::dvec3(0.0), 0.0};
  PostFromOrigin post_from_eye{glm::dvec3(0.0), glm::dvec2(0.0), 0.0, 0.0};
  LightingState lighting;
  glm::dvec3 ground_radiance_per_albedo;              // E_up / pi
  std::array<glm::dvec3, kPostAzimuthSteps> post_radiance;  // by world azimuth of the post's normal
  const OccluderFrame* occluders = nullptr;           // renderWithOccluders only
  const World::Lamp* lamp = nullptr;                  // renderWithOccluders only
  glm::dvec3 lamp_at_one_metre{0.0};                  // its irradiance over E_up per channel, 1 m below it
  bool occluders_only = false;                        // PixelWindow::occluders_only
};

}  // namespace

struct World::Impl {
  explicit Impl(const SceneConfig& config)
      : scene(config), coarse_floor_noise(config.seed), fine_floor_noise(config.seed + 7) {}
  SceneConfig scene;
  // The floor texture's two octaves.
  ValueNoise coarse_floor_noise, fine_floor_noise;
  std::unique_ptr<Environment> environment;
  std::unique_ptr<CameraPath> path;
  std::unique_ptr<TagPattern> tag;
  std::vector<float> rays_cam;  // 3 floats per sub-sample, unit length, pixel-major
  std::vector<float> corner_rays_cam;  // 3 floats per pixel corner, (width+1) x (height+1), row-major
  int samples_per_pixel = 1;
  double exposure = 1.0;
  SrgbEncoder srgb;
  glm::dvec3 lamp_radiance{0.0};
  // Rotation-invariant parts of the lighting, from the environment at
  // rotation 0 and from the lamp alone.
  glm::dvec3 environment_irradiance_up{0.0}, lamp_irradiance_up{0.0};
  std::array<glm::dvec3, kPostAzimuthSteps> environment_irradiance_horizontal{}, lamp_irradiance_horizontal{};

  mutable std::mutex cache_mutex;
  mutable std::map<std::pair<std::int64_t, bool>, std::shared_ptr<const TruthGrid>> truth_cache;
  mutable std::map<std::pair<std::int64_t, bool>, std::shared_ptr<const PieceRadiance>> piece_cache;

  LightingState lightingAt(std::uint64_t frame) const {
    LightingState state;
    state.environment_rotation_rad = degToRad(scene.environment_rotation_deg +
                                              scene.lighting.sun_azimuth_rate_deg_per_frame * static_cast<double>(frame));
    const auto& l = scene.lighting;
    const auto f = static_cast<std::int64_t>(frame);
    state.lamp_on = l.lamp_on_frame >= 0 && f >= l.lamp_on_frame && (l.lamp_off_frame < 0 || f < l.lamp_off_frame);
    return state;
  }

  double lampWeight(const glm::dvec3& dir) const {
    const auto& l = scene.lighting;
    double azimuth = std::atan2(dir.y, dir.x) * 180.0 / kPi;
    double elevation = std::asin(std::clamp(dir.z, -1.0, 1.0)) * 180.0 / kPi;
    double daz = std::abs(std::remainder(azimuth - l.lamp_azimuth_deg, 360.0));
    double del = std::abs(elevation - l.lamp_elevation_deg);
    auto edge = [](double inside) {  // 1 deg soft edge, as the procedural soft boxes
      double x = std::clamp(inside + 0.5, 0.0, 1.0);
      return x * x * (3 - 2 * x);
    };
    return edge(l.lamp_width_deg / 2 - daz) * edge(l.lamp_height_deg / 2 - del);
  }

  glm::dvec3 environmentRadiance(const glm::dvec3& dir, const LightingState& state) const {
    glm::dvec3 result = environment->radiance(rotateZ(dir, -state.environment_rotation_rad));
    if (state.lamp_on) result += lampWeight(dir) * lamp_radiance;
    return result;
  }

  glm::dvec3 irradianceUp(const LightingState& state) const {
    return environment_irradiance_up + (state.lamp_on ? lamp_irradiance_up : glm::dvec3(0.0));
  }

  double groundAlbedo(double x, double y, SceneObject& object, bool* tag_white = nullptr) const {
    bool is_white = false;
    if (tag->sample(x, y, is_white)) {
      if (tag_white) *tag_white = is_white;
      object = SceneObject::kTag;
      return is_white ? scene.tag_white_albedo : scene.tag_black_albedo;
    }
    object = SceneObject::kFloor;
    if (scene.floor_texture_contrast <= 0.0) return scene.floor_albedo;
    double texture = 0.65 * coarse_floor_noise(x / 0.09, y / 0.09) + 0.35 * fine_floor_noise(x / 0.027, y / 0.027);
    return std::clamp(scene.floor_albedo * (1.0 + scene.floor_texture_contrast * texture), 0.0, 1.0);
  }

  // The post's radiance where its normal points at world azimuth
  // `azimuth_rad`: the frame's table, interpolated linearly.
  static glm::dvec3 postRadiance(const FrameState& fs, double azimuth_rad) {
    double x = azimuth_rad / (2 * kPi) * kPostAzimuthSteps;
    x -= std::floor(x / kPostAzimuthSteps) * kPostAzimuthSteps;
    const int i0 = static_cast<int>(x) % kPostAzimuthSteps;
    const double f = x - std::floor(x);
    return (1 - f) * fs.post_radiance[i0] + f * fs.post_radiance[(i0 + 1) % kPostAzimuthSteps];
  }

  // The camera's part of a frame state: where it is and what its rays meet.
  void placeCamera(FrameState& fs, const PoseCamFromWorld& pose) const {
    fs.pose = pose;
    fs.world_from_cam = glm::transpose(fs.pose.R_cam_from_world);
    fs.eye = fs.pose.cameraCenterWorld();
    const RigGeometry& rig = scene.rig;
    fs.ball_from_eye = SphereFromOrigin(fs.eye, rig.probe_center_w, rig.probe_radius_m);
    fs.post_from_eye = PostFromOrigin(fs.eye, {rig.probe_center_w.x, rig.probe_center_w.y}, scene.post_radius_m,
                                      rig.probe_center_w.z - rig.probe_radius_m);
  }

  // The instants a shutter open for `shutter_frames` frame intervals,
  // centred on frame `frame` (so the frame's pose, the truth's, is the
  // middle of its exposure), is sampled at: n instants at the middles of n
  // equal parts of the exposure, each a whole frame state of `fs` with the
  // camera moved along the path. n is the most any of a few points moves
  // on screen across the exposure, rounded up (one instant when the camera
  // holds still): each instant is integrated over the pixel's area, and a
  // one-pixel box repeated at one-pixel steps is the continuous box a
  // steady motion draws, so the smear has no steps.
  std::vector<FrameState> shutterInstants(const FrameState& fs, std::uint64_t frame, double shutter_frames) const {
    if (!(shutter_frames > 0.0)) return {fs};
    const double middle = static_cast<double>(frame);
    const PoseCamFromWorld opens = path->poseAt(middle - 0.5 * shutter_frames);
    const PoseCamFromWorld closes = path->poseAt(middle + 0.5 * shutter_frames);
    const double most_moved_px = largestScreenMotionPx(fs, opens, closes);
    const int instants = std::clamp(static_cast<int>(std::ceil(most_moved_px)), 1, kMostShutterInstants);
    if (instants == 1) return {fs};
    std::vector<FrameState> result(static_cast<size_t>(instants), fs);
    for (int i = 0; i < instants; ++i)
      placeCamera(result[static_cast<size_t>(i)],
                  path->poseAt(middle + shutter_frames * ((i + 0.5) / instants - 0.5)));
    return result;
  }
  // A smear longer than this many pixels is sampled more coarsely (its
  // steps then show on sharp edges).
  static constexpr int kMostShutterInstants = 64;

  // The longest on-screen path (pinhole, px) from pose `a` to pose `b` of
  // the tag's corners, the ball's centre, and what the frame's corners and
  // centre see (the ground where their rays meet it, else far away).
  double largestScreenMotionPx(const FrameState& fs, const PoseCamFromWorld& a, const PoseCamFromWorld& b) const {
    std::vector<glm::dvec3> points_w;
    for (const glm::dvec3& corner : tagCornersWorld(scene.rig.tag_size_m)) points_w.push_back(corner);
    points_w.push_back(scene.rig.probe_center_w);
    const CameraIntrinsics& camera = scene.camera;
    const double xs[] = {0.0, camera.cx_px, camera.width_px - 1.0};
    const double ys[] = {0.0, camera.cy_px, camera.height_px - 1.0};
    for (double x : xs)
      for (double y : ys) {
        const glm::dvec3 dir = fs.world_from_cam * glm::normalize(glm::dvec3((x - camera.cx_px) / camera.fx_px,
                                                                             (y - camera.cy_px) / camera.fy_px, 1.0));
        constexpr double kFarM = 1000.0;
        const double to_ground_m = dir.z < 0.0 ? -fs.eye.z / dir.z : kFarM;
        points_w.push_back(fs.eye + std::min(to_ground_m, kFarM) * dir);
      }
    double most_px = 0.0;
    for (const glm::dvec3& point_w : points_w) {
      const glm::dvec3 in_a = a.R_cam_from_world * point_w + a.t_cam_from_world;
      const glm::dvec3 in_b = b.R_cam_from_world * point_w + b.t_cam_from_world;
      if (!(in_a.z > 0.0) || !(in_b.z > 0.0)) continue;
      const glm::dvec2 moved(camera.fx_px * (in_b.x / in_b.z - in_a.x / in_a.z),
                             camera.fy_px * (in_b.y / in_b.z - in_a.y / in_a.z));
      most_px = std::max(most_px, glm::length(moved));
    }
    return most_px;
  }

  FrameState frameState(std::uint64_t frame) const {
    FrameState fs;
    placeCamera(fs, path->pose(frame));
    fs.lighting = lightingAt(frame);
    glm::dvec3 e_up = irradianceUp(fs.lighting);
    fs.ground_radiance_per_albedo = e_up / kPi;
    for (int i = 0; i < kPostAzimuthSteps; ++i) {
      // The environment table is in the environment's own frame: look it up
      // at the world azimuth minus the rotation, with linear interpolation.
      double world_azimuth = 2 * kPi * i / kPostAzimuthSteps;
      double env_azimuth = world_azimuth - fs.lighting.environment_rotation_rad;
      double x = env_azimuth / (2 * kPi) * kPostAzimuthSteps;
      x -= std::floor(x / kPostAzimuthSteps) * kPostAzimuthSteps;
      int i0 = static_cast<int>(x) % kPostAzimuthSteps;
      int i1 = (i0 + 1) % kPostAzimuthSteps;
      double f = x - std::floor(x);
      glm::dvec3 e = (1 - f) * environment_irradiance_horizontal[i0] + f * environment_irradiance_horizontal[i1];
      if (fs.lighting.lamp_on) e += lamp_irradiance_horizontal[i];
      e += scene.floor_albedo * e_up / 2.0;  // uniform floor filling the lower half
      fs.post_radiance[i] = scene.post_albedo * e / kPi;
    }
    return fs;
  }

  glm::dvec3 groundRadiance(const glm::dvec3& point, const FrameState& fs, SceneObject& object,
                            bool* tag_white = nullptr) const {
    return groundAlbedo(point.x, point.y, object, tag_white) * fs.ground_radiance_per_albedo;
  }

  // The first object a camera ray hits, and the distance to it (+inf for the
  // environment); for an occluder, its index in fs.occluders.
  double firstHit(const glm::dvec3& dir, const FrameState& fs, SceneObject& object, int* occluder_index = nullptr) const {
    double t_best = std::numeric_limits<double>::infinity();
    object = SceneObject::kEnvironment;
    if (auto t = fs.ball_from_eye.intersect(dir)) {
      t_best = *t;
      object = SceneObject::kProbe;
    }
    if (auto t = fs.post_from_eye.intersect(dir); t && *t < t_best) {
      t_best = *t;
      object = SceneObject::kPost;
    }
    if (dir.z < 0.0) {
      double t = -fs.eye.z / dir.z;
      if (t > 0.0 && t < t_best) {
        t_best = t;
        object = SceneObject::kFloor;
      }
    }
    if (fs.occluders) {
      const std::vector<VirtualOccluder>& occluders = fs.occluders->shadow.occluders;
      for (size_t i = 0; i < occluders.size(); ++i)
        if (auto t = intersectOccluder(occluders[i], fs.eye, dir); t && *t < t_best) {
          t_best = *t;
          object = SceneObject::kOccluder;
          if (occluder_index) *occluder_index = static_cast<int>(i);
        }
    }
    return t_best;
  }

  // What a pixel edge can separate: the object, and on the tag its cell's
  // colour. Floor texture, sky and the ball's reflection vary smoothly
  // enough at the pixel scale for regular sub-samples.
  std::uint8_t edgeClass(const glm::dvec3& dir, const FrameState& fs) const {
    SceneObject object;
    int occluder = -1;
    double t = firstHit(dir, fs, object, &occluder);
    bool white = false;
    if (object == SceneObject::kFloor) {
      // Only whether the tag is printed there: the floor's texture (most of
      // a frame's cost) does not change the class.
      const glm::dvec3 p = fs.eye + t * dir;
      if (tag->sample(p.x, p.y, white)) object = SceneObject::kTag;
    }
    return classOf(object, white, occluder);
  }

  // Two occluders seen one over the other are told apart by their index.
  static std::uint8_t classOf(SceneObject object, bool tag_white, int occluder = -1) {
    const int occluder_bits = object == SceneObject::kOccluder ? (std::min(occluder, 14) + 1) << 4 : 0;
    return static_cast<std::uint8_t>(static_cast<int>(object) | (tag_white ? 8 : 0) | occluder_bits);
  }

  // Scene radiance along a camera ray, and the first object it hits (and, when
  // asked, its edgeClass, for free).
  // sample_share: the part of a pixel this ray stands for (a mesh's paths
  // are shared out among an edge pixel's sub-samples).
  glm::dvec3 shadeCameraRay(const glm::dvec3& dir, const FrameState& fs, SceneObject& object,
                            std::uint8_t* edge_class = nullptr, double sample_share = 1.0) const {
    bool white = false;
    int occluder = -1;
    const double t = firstHit(dir, fs, object, &occluder);
    if (fs.occluders_only && object != SceneObject::kOccluder) {
      if (edge_class) *edge_class = classOf(object, white, occluder);
      return glm::dvec3(0.0);
    }
    glm::dvec3 radiance = shadeHit(dir, fs, t, object, white, occluder, sample_share);
    if (edge_class) *edge_class = classOf(object, white, occluder);
    return radiance;
  }

  // The lamp's irradiance at ground point p over the room's (E_up), per
  // channel: zero where an occluder, the ball or its post stands between.
  glm::dvec3 lampOverRoom(const glm::dvec3& p, const FrameState& fs) const {
    const World::Lamp& lamp = *fs.lamp;
    const glm::dvec3 to_lamp = lamp.position_w - p;
    const double d = glm::length(to_lamp);
    if (!(d > 0.0) || !(to_lamp.z > 0.0)) return glm::dvec3(0.0);
    const glm::dvec3 dir = to_lamp / d;
    double spot = 1.0;
    if (lamp.spot_half_angle_deg < 180.0) {
      const double outer = std::cos(degToRad(std::min(lamp.spot_half_angle_deg + 0.5 * lamp.spot_softness_deg, 180.0)));
      const double inner =
          std::max(std::cos(degToRad(std::max(lamp.spot_half_angle_deg - 0.5 * lamp.spot_softness_deg, 0.0))),
                   outer + 1e-4);
      const double x = std::clamp((glm::dot(-dir, glm::normalize(lamp.spot_direction_w)) - outer) / (inner - outer),
                                  0.0, 1.0);
      spot = x * x * (3.0 - 2.0 * x);
    }
    if (!(spot > 0.0)) return glm::dvec3(0.0);
    // In the way: the ball (a sphere), its post (a vertical cylinder up to
    // the ball), an occluder.
    const RigGeometry& rig = scene.rig;
    const glm::dvec3 from_ball = p - rig.probe_center_w;
    const double b = glm::dot(from_ball, dir), c = glm::dot(from_ball, from_ball) - rig.probe_radius_m * rig.probe_radius_m;
    if (b * b - c > 0.0 && -b - std::sqrt(b * b - c) > 0.0 && -b - std::sqrt(b * b - c) < d) return glm::dvec3(0.0);
    if (scene.post_radius_m > 0.0) {
      const glm::dvec2 from_axis = glm::dvec2(p) - glm::dvec2(rig.probe_center_w);
      const glm::dvec2 across(dir);
      const double a2 = glm::dot(across, across), b2 = glm::dot(from_axis, across);
      const double c2 = glm::dot(from_axis, from_axis) - scene.post_radius_m * scene.post_radius_m;
      if (a2 > 0.0 && b2 * b2 - a2 * c2 > 0.0) {
        const double t = (-b2 - std::sqrt(b2 * b2 - a2 * c2)) / a2;
        if (t > 0.0 && t < d && p.z + t * dir.z < rig.probe_center_w.z - rig.probe_radius_m) return glm::dvec3(0.0);
      }
    }
    if (fs.occluders)
      for (const VirtualOccluder& occluder : fs.occluders->shadow.occluders)
        if (occluderBlocks(occluder, p + 1e-9 * dir, dir, d)) return glm::dvec3(0.0);
    return fs.lamp_at_one_metre * (to_lamp.z / (d * d * d) * spot);
  }

  // Radiance of the first hit at distance t_best along dir; `object` floor
  // becomes tag where the tag is printed.
  glm::dvec3 shadeHit(const glm::dvec3& dir, const FrameState& fs, double t_best, SceneObject& object,
                      bool& white, int occluder_index = -1, double sample_share = 1.0) const {
    const RigGeometry& rig = scene.rig;
    switch (object) {
      case SceneObject::kEnvironment:
        return environmentRadiance(dir, fs.lighting);
      case SceneObject::kFloor:
      case SceneObject::kTag: {
        const glm::dvec3 p = fs.eye + t_best * dir;
        const glm::dvec3 lit = groundRadiance(p, fs, object, &white);
        glm::dvec3 radiance = lit;
        if (fs.occluders) radiance *= shadowFraction({p.x, p.y}, *fs.occluders);
        if (fs.lamp) radiance += lit * lampOverRoom(p, fs);
        return radiance;
      }
      case SceneObject::kOccluder: {
        const VirtualOccluder& occluder = fs.occluders->shadow.occluders[static_cast<size_t>(occluder_index)];
        if (occluder.shape == VirtualOccluder::Shape::kMesh) return shadeMesh(dir, fs, occluder, sample_share);
        glm::dvec3 normal(0.0, 0.0, 1.0);
        intersectOccluder(occluder, fs.eye, dir, &normal);
        return occluder.albedo * fs.occluders->irradiance(normal) / kPi;
      }
      case SceneObject::kPost: {
        glm::dvec3 p = fs.eye + t_best * dir;
        return postRadiance(fs, std::atan2(p.y - rig.probe_center_w.y, p.x - rig.probe_center_w.x));
      }
      case SceneObject::kProbe: {
        glm::dvec3 p = fs.eye + t_best * dir;
        glm::dvec3 n = (p - rig.probe_center_w) / rig.probe_radius_m;
        glm::dvec3 reflected = dir - 2.0 * glm::dot(dir, n) * n;
        glm::dvec3 seen;
        if (reflected.z < 0.0) {
          SceneObject ignored;
          seen = groundRadiance(p + (-p.z / reflected.z) * reflected, fs, ignored);
        } else {
          seen = environmentRadiance(reflected, fs.lighting);
        }
        return rig.probe_reflectance * seen;
      }
    }
    return glm::dvec3(0.0);
  }

  glm::dvec3 cameraRay(size_t sample, const FrameState& fs) const {
    const float* r = &rays_cam[sample * 3];
    return fs.world_from_cam * glm::dvec3(r[0], r[1], r[2]);
  }

  // What the ball centre sees along dir, scene units.
  glm::dvec3 ballCentreRadiance(const glm::dvec3& dir, const LightingState& state) const {
    if (dir.z >= 0.0) return environmentRadiance(dir, state);
    const glm::dvec3& c = scene.rig.probe_center_w;
    glm::dvec3 hit = c + (-c.z / dir.z) * dir;
    SceneObject ignored;
    return groundAlbedo(hit.x, hit.y, ignored) * irradianceUp(state) / kPi;
  }

  std::shared_ptr<const TruthGrid> truthGrid(const LightingState& state) const {
    const auto key = std::make_pair(static_cast<std::int64_t>(std::llround(state.environment_rotation_rad * 1e9)),
                                    state.lamp_on);
    {
      std::lock_guard<std::mutex> lock(cache_mutex);
      auto found = truth_cache.find(key);
      if (found != truth_cache.end()) return found->second;
    }
    auto grid = std::make_shared<TruthGrid>();
    const auto& cells = directionGrid();
    grid->hdr.assign(cells.size(), glm::dvec3(0.0));
    grid->clipped.assign(cells.size(), glm::dvec3(0.0));
    const double reflectance = scene.rig.probe_reflectance;
    parallelRows(kGridHeight, std::max(1, scene.render_threads), [&](int r0, int r1, int) {
      for (int row = r0; row < r1; ++row)
        for (int col = 0; col < kGridWidth; ++col) {
          const int index = row * kGridWidth + col;
          glm::dvec3 hdr(0.0), clipped(0.0);
          double weight_sum = 0.0;
          cellMean(cells[index], [&](const glm::dvec3& dir, double w) {
            glm::dvec3 camera_linear = exposure * ballCentreRadiance(dir, state);
            hdr += w * camera_linear;
            clipped += w * glm::min(camera_linear * reflectance, glm::dvec3(1.0)) / reflectance;
            weight_sum += w;
          });
          grid->hdr[index] = hdr / weight_sum;
          grid->clipped[index] = clipped / weight_sum;
        }
    });
    std::lock_guard<std::mutex> lock(cache_mutex);
    if (truth_cache.size() >= 16) truth_cache.clear();  // bounded memory (6 MB a state)
    truth_cache.emplace(key, grid);
    return grid;
  }

  // ---- Shadow truth ----

  std::shared_ptr<const PieceRadiance> pieceRadiance(const LightingState& state) const {
    const auto key = std::make_pair(static_cast<std::int64_t>(std::llround(state.environment_rotation_rad * 1e9)),
                                    state.lamp_on);
    {
      std::lock_guard<std::mutex> lock(cache_mutex);
      auto found = piece_cache.find(key);
      if (found != piece_cache.end()) return found->second;
    }
    auto pieces = std::make_shared<PieceRadiance>();
    const LevelOnePieces& geometry = levelOnePieces();
    pieces->hdr.resize(geometry.dirs.size());
    constexpr size_t kPerCell = kShadowSplit * kShadowSplit;
    parallelRows(kUpperRows, std::max(1, scene.render_threads), [&](int r0, int r1, int) {
      for (size_t i = static_cast<size_t>(r0) * kGridWidth * kPerCell; i < static_cast<size_t>(r1) * kGridWidth * kPerCell; ++i)
        pieces->hdr[i] = glm::vec3(exposure * environmentRadiance(geometry.dirs[i], state));
    });
    std::lock_guard<std::mutex> lock(cache_mutex);
    if (piece_cache.size() >= 4) piece_cache.clear();  // bounded memory (7 MB a state)
    piece_cache.emplace(key, pieces);
    return pieces;
  }

  ShadowContext shadowContext(const LightingState& state, const std::vector<VirtualOccluder>& occluders) const {
    ShadowContext context;
    context.lighting = state;
    context.grid = truthGrid(state);
    context.pieces = pieceRadiance(state);
    context.occluders = occluders;
    // E_up from the same cells the blocked part is taken from, so that a
    // point whose whole sky is blocked gets exactly 0. It equals
    // exposure * groundIrradianceUp to the grid's ~1e-3 rotation error.
    const auto& cells = directionGrid();
    for (int row = 0; row < kUpperRows; ++row) {
      glm::dvec3 row_max(0.0);
      for (int col = 0; col < kGridWidth; ++col) {
        const size_t i = static_cast<size_t>(row) * kGridWidth + col;
        context.e_up_hdr += cells[i].moment.z * context.grid->hdr[i];
        context.e_up_clipped += cells[i].moment.z * context.grid->clipped[i];
        row_max = glm::max(row_max, context.grid->hdr[i]);
      }
      context.row_max_hdr[static_cast<size_t>(row)] = row_max;
    }
    context.refine_luminance = kShadowRefineShare * luminance(context.e_up_hdr);
    context.meshes_only = !occluders.empty();
    for (const VirtualOccluder& occluder : occluders) {
      if (occluder.shape == VirtualOccluder::Shape::kMesh)
        context.max_level = kMeshShadowMaxLevel;
      else
        context.meshes_only = false;
    }
    return context;
  }

  // One piece of sky, already classified: split further if it is cut and
  // bright enough, else counted whole, its blocked part decided by its centre.
  void addPiece(Visibility v, double theta0, double theta1, double phi0, double phi1, int level, const glm::dvec3& dir,
                double moment_z, const glm::dvec3& hdr, const glm::dvec3& point_w,
                const std::vector<OccluderCone>& cones, const ShadowContext& context, PieceSums& sums) const {
    if (v == Visibility::kCut && level < context.max_level && moment_z * luminance(hdr) > context.refine_luminance) {
      splitCutPiece(theta0, theta1, phi0, phi1, level + 1, point_w, cones, context, sums);
      return;
    }
    const double reflectance = scene.rig.probe_reflectance;
    const glm::dvec3 clipped = glm::min(hdr * reflectance, glm::dvec3(1.0)) / reflectance;
    sums.whole_hdr += moment_z * hdr;
    sums.whole_clipped += moment_z * clipped;
    if (v == Visibility::kCut) v = blockedAlong(cones, point_w, dir) ? Visibility::kBlocked : Visibility::kClear;
    if (v == Visibility::kBlocked) {
      sums.blocked_hdr += moment_z * hdr;
      sums.blocked_clipped += moment_z * clipped;
    }
  }

  // A cut piece (theta0..theta1, phi0..phi1) of level >= 2 as kShadowSplit^2
  // pieces with exact cosine moments and their own centre radiance.
  void splitCutPiece(double theta0, double theta1, double phi0, double phi1, int level, const glm::dvec3& point_w,
                     const std::vector<OccluderCone>& cones, const ShadowContext& context, PieceSums& sums) const {
    for (int i = 0; i < kShadowSplit; ++i) {
      const double t0 = theta0 + (theta1 - theta0) * i / kShadowSplit;
      const double t1 = theta0 + (theta1 - theta0) * (i + 1) / kShadowSplit;
      const double theta = 0.5 * (t0 + t1);
      // z component of the piece's cosine moment per radian of phi
      const double moment_z_per_phi = 0.5 * (std::sin(t1) * std::sin(t1) - std::sin(t0) * std::sin(t0));
      for (int j = 0; j < kShadowSplit; ++j) {
        const double p0 = phi0 + (phi1 - phi0) * j / kShadowSplit;
        const double p1 = phi0 + (phi1 - phi0) * (j + 1) / kShadowSplit;
        const double phi = 0.5 * (p0 + p1);
        const glm::dvec3 dir{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
        const double rho = 0.5 * (t1 - t0) + 0.5 * (p1 - p0) * std::sin(t1);
        const glm::dvec3 hdr = exposure * environmentRadiance(dir, context.lighting);
        const Visibility v = classifyAll(cones, dir, rho, std::sin(rho), std::cos(rho));
        addPiece(v, t0, t1, p0, p1, level, dir, (p1 - p0) * moment_z_per_phi, hdr, point_w, cones, context, sums);
      }
    }
  }

  // A cut cell as its level-1 pieces, from the tabulated geometry and radiance.
  void splitCutCell(size_t cell_index, int row, const glm::dvec3& point_w, const std::vector<OccluderCone>& cones,
                    const ShadowContext& context, PieceSums& sums) const {
    const LevelOnePieces& geometry = levelOnePieces();
    const GridCell& cell = directionGrid()[cell_index];
    constexpr size_t kPerCell = kShadowSplit * kShadowSplit;
    for (int i = 0; i < kShadowSplit; ++i) {
      const size_t k = static_cast<size_t>(row) * kShadowSplit + i;
      const double t0 = cell.theta0 + (cell.theta1 - cell.theta0) * i / kShadowSplit;
      const double t1 = cell.theta0 + (cell.theta1 - cell.theta0) * (i + 1) / kShadowSplit;
      for (int j = 0; j < kShadowSplit; ++j) {
        const size_t piece = cell_index * kPerCell + static_cast<size_t>(i * kShadowSplit + j);
        const glm::dvec3& dir = geometry.dirs[piece];
        const Visibility v = classifyAll(cones, dir, geometry.rho_rad[k], geometry.sin_rho[k], geometry.cos_rho[k]);
        const double p0 = cell.phi0 + (cell.phi1 - cell.phi0) * j / kShadowSplit;
        const double p1 = cell.phi0 + (cell.phi1 - cell.phi0) * (j + 1) / kShadowSplit;
        addPiece(v, t0, t1, p0, p1, 1, dir, geometry.moment_z[k], glm::dvec3(context.pieces->hdr[piece]), point_w, cones,
                 context, sums);
      }
    }
  }

  World::GroundShadowTruth shadowAt(const glm::dvec2& ground_point_w, const ShadowContext& context) const {
    World::GroundShadowTruth result;
    if (context.occluders.empty()) return result;
    const glm::dvec3 point_w{ground_point_w.x, ground_point_w.y, 0.0};
    const UpperCellGeometry& geometry = upperCellGeometry();
    const auto& cells = directionGrid();
    const double row_height_rad = kPi / kGridHeight;
    std::vector<OccluderCone> cones;
    cones.reserve(context.occluders.size());
    // Only rows that a bounding cone (grown by a cell's radius) reaches.
    int row_begin = kUpperRows, row_end = 0;
    for (const VirtualOccluder& occluder : context.occluders) {
      cones.push_back(coneFrom(occluder, point_w));
      const OccluderCone& cone = cones.back();
      if (cone.inside_bound || cone.blocks_everything) {
        row_begin = 0;
        row_end = kUpperRows;
        continue;
      }
      const double theta_axis = std::acos(std::clamp(cone.axis.z, -1.0, 1.0));
      const double reach = cone.half_angle_rad + geometry.max_rho_rad;
      row_begin = std::min(row_begin, std::max(0, static_cast<int>(std::floor((theta_axis - reach) / row_height_rad))));
      row_end = std::max(row_end, std::min(kUpperRows, static_cast<int>(std::floor((theta_axis + reach) / row_height_rad)) + 1));
    }
    glm::dvec3 blocked_hdr(0.0), blocked_clipped(0.0);
    auto ratio = [](const glm::dvec3& part, const glm::dvec3& whole) {
      glm::dvec3 r(0.0);
      for (int c = 0; c < 3; ++c) r[c] = whole[c] > 0.0 ? part[c] / whole[c] : 0.0;
      return r;
    };
    for (int row = row_begin; row < row_end; ++row) {
      const size_t r = static_cast<size_t>(row);
      for (int block = 0; block < kBlocksPerRow; ++block) {
        const Visibility block_visibility =
            classifyAll(cones, geometry.block_dirs[r * kBlocksPerRow + static_cast<size_t>(block)],
                        geometry.block_rho_rad[r], geometry.block_sin_rho[r], geometry.block_cos_rho[r]);
        if (block_visibility == Visibility::kClear) continue;
        for (int col = block * kColumnBlock; col < (block + 1) * kColumnBlock; ++col) {
          const size_t i = r * kGridWidth + static_cast<size_t>(col);
          Visibility v = block_visibility == Visibility::kBlocked
                                   ? Visibility::kBlocked
                                   : classifyAll(cones, geometry.centre_dirs[i], geometry.rho_rad[r],
                                                 geometry.sin_rho[r], geometry.cos_rho[r]);
          if (v == Visibility::kClear) continue;
          const double moment_z = cells[i].moment.z;
          if (v == Visibility::kCut && context.meshes_only &&
              moment_z * luminance(context.grid->hdr[i]) <= kShadowSplit * kShadowSplit * context.refine_luminance)
            v = blockedAlong(cones, point_w, geometry.centre_dirs[i]) ? Visibility::kBlocked : Visibility::kClear;
          if (v == Visibility::kClear) continue;
          if (v == Visibility::kBlocked) {
            blocked_hdr += moment_z * context.grid->hdr[i];
            blocked_clipped += moment_z * context.grid->clipped[i];
            continue;
          }
          // Cut: the blocked share of the cell's own pieces, applied to the
          // cell's cached radiance, so that a wholly blocked cell counts
          // exactly as in E_up.
          PieceSums sums;
          splitCutCell(i, row, point_w, cones, context, sums);
          blocked_hdr += moment_z * context.grid->hdr[i] * ratio(sums.blocked_hdr, sums.whole_hdr);
          blocked_clipped += moment_z * context.grid->clipped[i] * ratio(sums.blocked_clipped, sums.whole_clipped);
        }
      }
    }
    // The clamp only absorbs rounding: blocked <= E_up cell by cell.
    result.hdr = glm::clamp(glm::dvec3(1.0) - ratio(blocked_hdr, context.e_up_hdr), 0.0, 1.0);
    result.clipped = glm::clamp(glm::dvec3(1.0) - ratio(blocked_clipped, context.e_up_clipped), 0.0, 1.0);
    return result;
  }

  // Upper bound of 1 - hdr fraction at a ground point, per channel, without
  // integrating: each occluder's blocked light is at most the brightest cell
  // in the rows its cone can touch times the projected solid angle of the
  // cone grown by a cell's diameter (the cells it can touch).
  glm::dvec3 shadowDeficitBound(const glm::dvec2& ground_point_w, const ShadowContext& context) const {
    const double max_rho = upperCellGeometry().max_rho_rad;
    const double row_height_rad = kPi / kGridHeight;
    glm::dvec3 bound(0.0);
    for (const VirtualOccluder& occluder : context.occluders) {
      const OccluderBound sphere = occluderBound(occluder);
      const glm::dvec3 to_center = sphere.center_w - glm::dvec3(ground_point_w, 0.0);
      const double distance_m = glm::length(to_center);
      if (distance_m <= sphere.radius_m * (1.0 + 1e-9)) return glm::dvec3(std::numeric_limits<double>::infinity());
      const double grown = std::asin(sphere.radius_m / distance_m) + 2.0 * max_rho;
      const double elevation = std::asin(std::clamp(to_center.z / distance_m, -1.0, 1.0));
      const double theta_low = kPi / 2 - (elevation + grown), theta_high = kPi / 2 - (elevation - grown);
      const int row_begin = std::max(0, static_cast<int>(std::floor(theta_low / row_height_rad)));
      const int row_end = std::min(kUpperRows, static_cast<int>(std::floor(theta_high / row_height_rad)) + 1);
      glm::dvec3 brightest(0.0);
      for (int row = row_begin; row < row_end; ++row) brightest = glm::max(brightest, context.row_max_hdr[static_cast<size_t>(row)]);
      const double highest_cos = elevation + grown >= kPi / 2 ? 1.0 : std::sin(elevation + grown);
      const double projected_solid_angle = 2.0 * kPi * (1.0 - std::cos(std::min(grown, kPi))) * highest_cos;
      bound += brightest * projected_solid_angle;
    }
    for (int c = 0; c < 3; ++c) bound[c] = context.e_up_hdr[c] > 0.0 ? bound[c] / context.e_up_hdr[c] : 0.0;
    return bound;
  }

  // The hdr fraction renderWithOccluders applies at a grid node: exact, with
  // deficits under kIgnoredShadowDeficit dropped.
  glm::dvec3 nodeFraction(const glm::dvec2& node_w, const ShadowContext& context) const {
    auto negligible = [](const glm::dvec3& deficit) {
      return deficit.r < World::kIgnoredShadowDeficit && deficit.g < World::kIgnoredShadowDeficit &&
             deficit.b < World::kIgnoredShadowDeficit;
    };
    if (negligible(shadowDeficitBound(node_w, context))) return glm::dvec3(1.0);
    const glm::dvec3 fraction = shadowAt(node_w, context).hdr;
    return negligible(glm::dvec3(1.0) - fraction) ? glm::dvec3(1.0) : fraction;
  }

  // Hdr shadow fraction at a visible ground point for renderWithOccluders:
  // bilinear in a grid of exact node values (2 mm near the occluders, coarser
  // further out; filled on demand, shared by the threads). Nodes strictly
  // inside a box's footprint are left out and the weights renormalised:
  // there the true value (0) is not the limit of the visible ground's, which
  // is ~0.5 at a wall's foot. Points whose bound says the deficit is
  // negligible skip the grid altogether.
  glm::dvec3 shadowFraction(const glm::dvec2& ground_point_w, const OccluderFrame& frame) const {
    const ShadowContext& context = frame.shadow;
    if (!(std::abs(ground_point_w.x) < kShadowFarLimit_m && std::abs(ground_point_w.y) < kShadowFarLimit_m))
      return glm::dvec3(1.0);
    const glm::dvec3 bound = shadowDeficitBound(ground_point_w, context);
    if (bound.r < World::kIgnoredShadowDeficit && bound.g < World::kIgnoredShadowDeficit &&
        bound.b < World::kIgnoredShadowDeficit)
      return glm::dvec3(1.0);
    double nearest_m = std::numeric_limits<double>::infinity();
    for (const VirtualOccluder& occluder : context.occluders)
      nearest_m = std::min(nearest_m, glm::length(ground_point_w - glm::dvec2(occluderBound(occluder).center_w)));
    const int level = nearest_m < kShadowFineReach_m
                          ? 0
                          : std::min(kShadowCoarsestLevel, 1 + static_cast<int>(std::log2(nearest_m / kShadowFineReach_m)));
    const double spacing_m = kShadowNodeSpacing_m * static_cast<double>(1 << level);
    const double fx = ground_point_w.x / spacing_m, fy = ground_point_w.y / spacing_m;
    const auto ix = static_cast<std::int64_t>(std::floor(fx)), iy = static_cast<std::int64_t>(std::floor(fy));
    const double u = fx - static_cast<double>(ix), v = fy - static_cast<double>(iy);
    std::array<std::uint64_t, 4> keys{};
    std::array<glm::dvec2, 4> nodes{};
    std::array<double, 4> weights{};
    std::array<bool, 4> known{};
    std::array<glm::dvec3, 4> values{};
    for (int k = 0; k < 4; ++k) {
      const std::int64_t nx = ix + (k & 1), ny = iy + (k >> 1);
      // level in the top 8 bits, then 28 bits of each index (|x| < 1000 m
      // is under 2^19 nodes at 2 mm)
      constexpr std::uint64_t kIndexMask = (1ull << 28) - 1;
      keys[k] = (static_cast<std::uint64_t>(level) << 56) | ((static_cast<std::uint64_t>(nx) & kIndexMask) << 28) |
                (static_cast<std::uint64_t>(ny) & kIndexMask);
      nodes[k] = glm::dvec2(static_cast<double>(nx), static_cast<double>(ny)) * spacing_m;
      weights[k] = ((k & 1) ? u : 1.0 - u) * ((k >> 1) ? v : 1.0 - v);
      for (const VirtualOccluder& occluder : context.occluders) {
        if (occluder.shape != VirtualOccluder::Shape::kBox) continue;
        const glm::dvec3 q = boxLocalFromWorldDirection(occluder, glm::dvec3(nodes[k], 0.0) - boxCenterWorld(occluder));
        if (std::abs(q.x) < 0.5 * occluder.box_size_m.x && std::abs(q.y) < 0.5 * occluder.box_size_m.y) weights[k] = 0.0;
      }
    }
    {
      std::lock_guard<std::mutex> lock(frame.node_mutex);
      for (int k = 0; k < 4; ++k) {
        auto found = frame.node_fraction.find(keys[k]);
        if (found != frame.node_fraction.end()) {
          known[k] = true;
          values[k] = found->second;
        }
      }
    }
    // Computed outside the lock; two threads may both compute a node, with
    // the same result, so the frame stays deterministic.
    for (int k = 0; k < 4; ++k) {
      if (known[k] || weights[k] == 0.0) continue;
      values[k] = nodeFraction(nodes[k], context);
      std::lock_guard<std::mutex> lock(frame.node_mutex);
      frame.node_fraction.emplace(keys[k], values[k]);
    }
    double weight_sum = 0.0;
    glm::dvec3 fraction(0.0);
    for (int k = 0; k < 4; ++k) {
      weight_sum += weights[k];
      fraction += weights[k] * values[k];
    }
    // All four nodes inside a footprint (a point at its very edge): exact.
    if (!(weight_sum > 0.0)) return nodeFraction(ground_point_w, context);
    return fraction / weight_sum;
  }

  // What an 8-bit camera can know of the sky through the ball, direction
  // by direction: the camera clips each of the ball's pixels, i.e. the mean
  // of the light over the pixel's footprint of directions, not each
  // direction's own light. A lamp smaller than a pixel clips the whole
  // pixel: the kiosk then knows the pixel's clipped value, spread over its
  // directions, which is more than the lamp's own directions clipped one
  // by one (those give the lamp only its own solid angle's worth of the
  // clip). So each cell's light is scaled by its pixel's clip ratio,
  // min(1, 1 / v) per channel with v the pixel's unclipped camera-linear
  // value (the ball's reflectance in it), found by tracing the ball's
  // pixels in this frame's view. The cell's pixel is where the ball
  // reflects the cell's direction to the eye: the point whose normal halves
  // the direction and the way to the eye (fixed-point steps from the
  // centre's). Cells behind the ball (facing away from the eye) or out of
  // the frame get -1.
  std::vector<glm::dvec3> ballPixelClipScale(const FrameState& fs) const {
    const RigGeometry& rig = scene.rig;
    const int width = scene.camera.width_px, height = scene.camera.height_px;
    const ProbeOutline outline = probeOutline(scene.camera, fs.pose, rig.probe_center_w, rig.probe_radius_m);
    const size_t cells = static_cast<size_t>(kUpperRows) * kGridWidth;
    std::vector<glm::dvec3> scale(cells, glm::dvec3(-1.0));
    if (!outline.valid) return scale;
    World::PixelWindow window{width, height, 0, 0, false};
    for (const glm::dvec2& p : outline.polygon_px) {
      window.x_begin = std::min(window.x_begin, static_cast<int>(std::floor(p.x)) - 1);
      window.y_begin = std::min(window.y_begin, static_cast<int>(std::floor(p.y)) - 1);
      window.x_end = std::max(window.x_end, static_cast<int>(std::ceil(p.x)) + 2);
      window.y_end = std::max(window.y_end, static_cast<int>(std::ceil(p.y)) + 2);
    }
    std::vector<glm::dvec3> linear(static_cast<size_t>(width) * height, glm::dvec3(0.0));
    std::vector<std::uint8_t> shows_ball(linear.size(), 0);
    FrameState plain = fs;
    plain.occluders = nullptr;  // the ball's reflection ignores the occluders
    traceFrame(plain, &window, [&](size_t pixel, const glm::dvec3& sum, const std::vector<SceneObject>& objects) {
      linear[pixel] = exposure * sum;
      shows_ball[pixel] = std::find(objects.begin(), objects.end(), SceneObject::kProbe) != objects.end();
    });
    const glm::dvec3& centre = rig.probe_center_w;
    const UpperCellGeometry& geometry = upperCellGeometry();
    std::vector<glm::dvec3> points(cells);
    std::vector<std::uint8_t> facing(cells, 0);
    for (size_t i = 0; i < cells; ++i) {
      const glm::dvec3& dir = geometry.centre_dirs[i];
      glm::dvec3 to_eye = glm::normalize(fs.eye - centre), normal(0.0, 0.0, 1.0);
      for (int step = 0; step < 4; ++step) {
        const glm::dvec3 half = dir + to_eye;
        if (!(glm::length(half) > 1e-9)) break;
        normal = glm::normalize(half);
        to_eye = glm::normalize(fs.eye - (centre + rig.probe_radius_m * normal));
      }
      points[i] = centre + rig.probe_radius_m * normal;
      facing[i] = glm::dot(normal, to_eye) > 1e-6;
    }
    const std::vector<glm::dvec2> pixels = projectWorldPoints(scene.camera, fs.pose, points);
    for (size_t i = 0; i < cells; ++i) {
      if (!facing[i]) continue;
      const long x = std::lround(pixels[i].x), y = std::lround(pixels[i].y);
      if (x < 0 || y < 0 || x >= width || y >= height) continue;
      const size_t pixel = static_cast<size_t>(y) * width + static_cast<size_t>(x);
      if (!shows_ball[pixel]) continue;
      for (int c = 0; c < 3; ++c) scale[i][c] = linear[pixel][c] > 1.0 ? 1.0 / linear[pixel][c] : 1.0;
    }
    return scale;
  }

  std::unique_ptr<OccluderFrame> occluderFrame(const FrameState& fs, const std::vector<VirtualOccluder>& occluders) const {
    const LightingState& state = fs.lighting;
    auto frame = std::make_unique<OccluderFrame>();
    frame->shadow = shadowContext(state, occluders);
    frame->irradiance_by_normal.assign(static_cast<size_t>(kIrradianceTableWidth) * kIrradianceTableHeight, glm::dvec3(0.0));
    const TruthGrid& grid = *frame->shadow.grid;
    parallelRows(kIrradianceTableHeight, std::max(1, scene.render_threads), [&](int r0, int r1, int) {
      for (int row = r0; row < r1; ++row) {
        const double theta = kPi * row / (kIrradianceTableHeight - 1);
        for (int col = 0; col < kIrradianceTableWidth; ++col) {
          const double phi = 2.0 * kPi * col / kIrradianceTableWidth;
          const glm::dvec3 normal{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
          // World::irradiance's integral, back in scene units.
          frame->irradiance_by_normal[static_cast<size_t>(row) * kIrradianceTableWidth + col] =
              integrateCosine(grid.hdr, normal) / exposure;
        }
      }
    });
    bool hdr_needed = false, clipped_needed = false;
    for (const VirtualOccluder& occluder : occluders)
      if (occluder.shape == VirtualOccluder::Shape::kMesh) (occluder.clipped_lighting ? clipped_needed : hdr_needed) = true;
    // The HDR sampler also draws the floor's shadow rays (meshFloorRadiance),
    // whatever light the model is shaded with.
    if (hdr_needed || clipped_needed) frame->sky_hdr.build(grid.hdr);
    if (clipped_needed) {
      frame->sky_clip_scale = ballPixelClipScale(fs);
      std::vector<glm::dvec3> clipped = grid.clipped;
      for (size_t i = 0; i < frame->sky_clip_scale.size(); ++i)
        if (frame->sky_clip_scale[i].x >= 0.0) clipped[i] = grid.hdr[i] * frame->sky_clip_scale[i];
      frame->sky_clipped.build(clipped);
    }
    return frame;
  }

  // ---- A model's truth: path tracing ----
  //
  // The radiance a real copy of the model sends to the eye: its glTF
  // material (sim/gltf_brdf, the specification's BRDF) integrated against
  // everything it sees, by Monte Carlo paths with two strategies combined
  // by the balance heuristic (Veach's multiple importance sampling): a
  // direction drawn from the sky's brightness (SkySampler) with a shadow ray,
  // and one drawn from the BRDF, which follows the path on when it meets the
  // model again (interreflection, up to max_bounces) and otherwise takes the
  // floor's or the sky's radiance. The floor is the world's own Lambertian
  // floor and tag, darkened by the occluders' shadow (shadowFraction): what
  // a model standing on it really sees below. Left out, each a small share
  // of what a model on the floor beside the tag receives: the light the
  // ball and its post reflect or hide, and the model's own light bounced
  // by the floor (the floor is lit by the sky alone, as in render()).

  // The sky along dir (unit, upward), scene units: the full HDR, or what an
  // 8-bit camera can know of it through the ball (ballPixelClipScale; where
  // no pixel shows it, the direction's own light clipped).
  glm::dvec3 meshSkyRadiance(const glm::dvec3& dir, const FrameState& fs, bool clipped) const {
    const glm::dvec3 radiance = environmentRadiance(dir, fs.lighting);
    if (!clipped) return radiance;
    const std::vector<glm::dvec3>& scale = fs.occluders->sky_clip_scale;
    if (!scale.empty() && dir.z > 0.0) {
      const glm::dvec3& s = scale[SkySampler::upperCellOf(dir)];
      if (s.x >= 0.0) return radiance * s;
    }
    const double reflectance = scene.rig.probe_reflectance;
    return glm::min(radiance * exposure * reflectance, glm::dvec3(1.0)) / (reflectance * exposure);
  }

  // The floor at point_w as a path from the model meets it: the world's
  // Lambertian floor, lit by the sky less what the occluders hide from it.
  // The hidden share is estimated by one shadow ray towards a direction
  // drawn from the sky's brightness (unbiased: E_hidden = E[L cos V / pdf]),
  // not read from the exact ground-shadow grid the visible floor uses: the
  // paths reach thousands of floor points under and around a model, and
  // the grid's exact nodes there (thousands of rays each) cost the truth
  // frame tens of seconds, where one ray a path adds noise the path's own
  // sampling already has.
  glm::dvec3 meshFloorRadiance(const glm::dvec3& point_w, const FrameState& fs, bool clipped, double u1, double u2,
                               double u3) const {
    SceneObject ignored;
    glm::dvec3 radiance = groundRadiance(point_w, fs, ignored);
    // What the ball's camera knows of the floor is the floor itself, clipped
    // as any radiance it sees (World::irradiance's lower hemisphere): not the
    // floor as a clipped sky would light it. The clip is taken on the
    // unshadowed floor and scales the estimate (a shadow only darkens: the
    // same as clipping the shadowed floor wherever the open floor is under
    // the clip, as the camera's exposure keeps it), so that a noisy
    // estimate is never bent by it.
    if (clipped) {
      const double reflectance = scene.rig.probe_reflectance;
      radiance = glm::min(radiance * exposure * reflectance, glm::dvec3(1.0)) / (reflectance * exposure);
    }
    double pdf = 0.0;
    const glm::dvec3 to_sky = fs.occluders->sky_hdr.sample(u1, u2, u3, pdf);
    if (pdf > 0.0 && to_sky.z > 0.0) {
      bool hidden = false;
      for (const VirtualOccluder& occluder : fs.occluders->shadow.occluders)
        if (occluderBlocks(occluder, point_w, to_sky)) {
          hidden = true;
          break;
        }
      if (hidden) {
        const glm::dvec3 e_up = kPi * fs.ground_radiance_per_albedo;
        const glm::dvec3 hidden_irradiance = environmentRadiance(to_sky, fs.lighting) * to_sky.z / pdf;
        for (int c = 0; c < 3; ++c)
          radiance[c] *= e_up[c] > 0.0 ? 1.0 - hidden_irradiance[c] / e_up[c] : 1.0;
      }
    }
    return radiance;
  }

  // The surface at a hit as the path sees it: its material, and a normal on
  // the side the ray came from (the back of a single-sided triangle is
  // shaded as its front: a real object has no invisible side), bent back
  // towards the viewer where interpolated normals tilt past the horizon.
  struct MeshSurface {
    GltfSurface material;
    glm::dvec3 point_w{0.0}, normal{0.0, 0.0, 1.0};
  };
  static MeshSurface meshSurface(const VirtualOccluder& mesh, const TriangleHit& hit, const glm::dvec3& origin,
                                 const glm::dvec3& dir) {
    MeshSurface surface;
    surface.material = surfaceAt(*mesh.model, hit);
    surface.point_w = origin + hit.t * dir;
    const glm::dvec3 geometric = hit.back_face ? -hit.geometric_normal : hit.geometric_normal;
    glm::dvec3 n = hit.back_face ? -hit.shading_normal : hit.shading_normal;
    const double n_dot_v = -glm::dot(n, dir);
    if (!(n_dot_v > 1e-4)) n = glm::normalize(n + (1e-4 - n_dot_v) * -dir);
    if (!std::isfinite(n.x) || glm::dot(n, geometric) <= 0.0) n = geometric;
    surface.normal = n;
    return surface;
  }

  glm::dvec3 shadeMesh(const glm::dvec3& dir, const FrameState& fs, const VirtualOccluder& mesh,
                       double sample_share) const {
    const std::optional<TriangleHit> first = intersectMesh(mesh, fs.eye, dir, std::numeric_limits<double>::infinity());
    if (!first) return glm::dvec3(0.0);  // firstHit found it; rounding on an edge may not
    const bool clipped = mesh.clipped_lighting;
    const SkySampler& sky = clipped ? fs.occluders->sky_clipped : fs.occluders->sky_hdr;
    const MeshSurface start = meshSurface(mesh, *first, fs.eye, dir);
    // Random numbers from the ray alone: the same frame gives the same bytes.
    std::uint64_t state = splitMix64(std::hash<double>{}(dir.x) ^ splitMix64(std::hash<double>{}(dir.y)) ^
                                     splitMix64(splitMix64(std::hash<double>{}(dir.z))));
    auto uniform = [&state] {
      state = splitMix64(state);
      return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    const int paths = std::max(1, static_cast<int>(std::lround(mesh.path_samples * sample_share)));
    glm::dvec3 sum(0.0);
    for (int path = 0; path < paths; ++path) {
      MeshSurface at = start;
      glm::dvec3 view = -dir, throughput(1.0), radiance = at.material.emissive;
      for (int bounce = 0;; ++bounce) {
        const GltfSurface& material = at.material;
        // The sky, drawn by its brightness.
        double sky_pdf = 0.0;
        const glm::dvec3 to_sky = sky.sample(uniform(), uniform(), uniform(), sky_pdf);
        const glm::dvec3 f_sky = gltf_brdf::evaluate(at.normal, view, to_sky, material);
        if (sky_pdf > 0.0 && (f_sky.r > 0.0 || f_sky.g > 0.0 || f_sky.b > 0.0) &&
            !occluderBlocks(mesh, at.point_w, to_sky)) {
          const double brdf_pdf = gltf_brdf::pdf(at.normal, view, to_sky, material);
          radiance += throughput * f_sky * meshSkyRadiance(to_sky, fs, clipped) / (sky_pdf + brdf_pdf);
        }
        // The BRDF's own direction.
        const gltf_brdf::BrdfSample next = gltf_brdf::sampleDirection(at.normal, view, material, uniform(), uniform(), uniform());
        if (!(next.pdf > 0.0)) break;
        const glm::dvec3 f = gltf_brdf::evaluate(at.normal, view, next.l, material);
        if (!(f.r > 0.0 || f.g > 0.0 || f.b > 0.0)) break;
        const glm::dvec3 weight = f / next.pdf;
        const std::optional<TriangleHit> hit =
            intersectMesh(mesh, at.point_w, next.l, std::numeric_limits<double>::infinity());
        if (hit) {
          if (bounce >= mesh.max_bounces) break;
          throughput *= weight;
          at = meshSurface(mesh, *hit, at.point_w, next.l);
          view = -next.l;
          radiance += throughput * at.material.emissive;
          continue;
        }
        if (next.l.z < 0.0) {
          const glm::dvec3 ground = at.point_w + (-at.point_w.z / next.l.z) * next.l;
          radiance += throughput * weight * meshFloorRadiance(ground, fs, clipped, uniform(), uniform(), uniform());
        } else {
          const double sky_density = sky.pdf(next.l);
          radiance += throughput * f * meshSkyRadiance(next.l, fs, clipped) / (next.pdf + sky_density);
        }
        break;
      }
      sum += radiance;
    }
    return sum / static_cast<double>(paths);
  }

  // render()'s sensor model for a prepared frame state.
  // `exposure_ev`: stops from the scene's exposure (a bracket frame).
  // `shutter_frames`: how long the shutter is open, in frame intervals
  // (motion blur; 0: an instant).
  void renderFrame(const FrameState& fs, std::uint64_t frame_index, ImageRGB8& out, double exposure_ev = 0.0,
                   const World::PixelWindow* window = nullptr, const glm::dvec3& channel_gain = glm::dvec3(1.0),
                   double shutter_frames = 0.0) const {
    out.resize(scene.camera.width_px, scene.camera.height_px);
    const glm::dvec3 scale = exposure * std::exp2(exposure_ev) * channel_gain;
    const float sigma = static_cast<float>(scene.noise_sigma_code);
    const std::vector<float>& gaussian = gaussianTable();
    std::uint64_t frame_salt = splitMix64(scene.seed ^ splitMix64(frame_index));
    // Each exposure of a bracket has noise of its own, as a sensor's frames do.
    if (exposure_ev != 0.0) frame_salt = splitMix64(frame_salt + static_cast<std::uint64_t>(std::llround(exposure_ev * 1024.0)));
    std::uint8_t* pixels = out.pixels.data();
    auto sense = [&](size_t pixel, const glm::dvec3& linear) {
      // Noise is a function of (seed, frame, pixel) only, so threads and
      // render order cannot change it.
      std::uint64_t bits = splitMix64(frame_salt + pixel);
      for (int c = 0; c < 3; ++c) {
        float code = srgb.encode(linear[c]);
        if (sigma > 0.0f)
          code += sigma * gaussian[(bits >> (kGaussianTableBits * c)) & (kGaussianTableSize - 1)];
        // Clamped first, so adding a half and truncating rounds to nearest
        // (lround is a library call, a tenth of a frame's time).
        pixels[pixel * 3 + c] = static_cast<std::uint8_t>(std::clamp(code, 0.0f, 255.0f) + 0.5f);
      }
    };
    const std::vector<FrameState> instants = shutterInstants(fs, frame_index, shutter_frames);
    if (!(scene.lens_blur_sigma_px > 0.0) && instants.size() == 1) {
      traceFrame(fs, window, [&](size_t pixel, const glm::dvec3& sum, const std::vector<SceneObject>&) {
        sense(pixel, sum * scale);
      });
      return;
    }
    renderBlurred(instants, window, scale, sense);
  }

  // The camera's linear light averaged over the shutter's instants (motion
  // blur), then the lens blur (SceneConfig::lens_blur_sigma_px) over it,
  // then `sense` per pixel of the window. The window is traced grown by the
  // kernel's radius (within the frame, whose edge pixels repeat outward),
  // so each of its pixels is what the whole frame gives it.
  template <typename Sense>
  void renderBlurred(const std::vector<FrameState>& instants, const World::PixelWindow* window,
                     const glm::dvec3& scale, Sense sense) const {
    const int width = scene.camera.width_px, height = scene.camera.height_px;
    const std::vector<double> kernel = lensBlurKernel(scene.lens_blur_sigma_px);
    const int radius = static_cast<int>(kernel.size() / 2);
    World::PixelWindow wanted{0, 0, width, height, false};
    if (window) wanted = *window;
    wanted.x_begin = std::clamp(wanted.x_begin, 0, width);
    wanted.x_end = std::clamp(wanted.x_end, wanted.x_begin, width);
    wanted.y_begin = std::clamp(wanted.y_begin, 0, height);
    wanted.y_end = std::clamp(wanted.y_end, wanted.y_begin, height);
    World::PixelWindow traced = wanted;
    traced.x_begin = std::max(0, wanted.x_begin - radius);
    traced.x_end = std::min(width, wanted.x_end + radius);
    traced.y_begin = std::max(0, wanted.y_begin - radius);
    traced.y_end = std::min(height, wanted.y_end + radius);
    std::vector<glm::dvec3> linear(static_cast<size_t>(width) * height, glm::dvec3(0.0));
    const glm::dvec3 instant_scale = scale / static_cast<double>(instants.size());
    for (const FrameState& fs : instants)
      traceFrame(fs, &traced, [&](size_t pixel, const glm::dvec3& sum, const std::vector<SceneObject>&) {
        linear[pixel] += sum * instant_scale;
      });
    auto at = [&](int x, int y) -> const glm::dvec3& {
      return linear[static_cast<size_t>(std::clamp(y, 0, height - 1)) * width + std::clamp(x, 0, width - 1)];
    };
    // Along rows, for the window's columns and the traced rows; then along
    // columns for the window.
    std::vector<glm::dvec3> rows(static_cast<size_t>(width) * height, glm::dvec3(0.0));
    for (int y = traced.y_begin; y < traced.y_end; ++y)
      for (int x = wanted.x_begin; x < wanted.x_end; ++x) {
        glm::dvec3 sum(0.0);
        for (int k = -radius; k <= radius; ++k) sum += kernel[static_cast<size_t>(k + radius)] * at(x + k, y);
        rows[static_cast<size_t>(y) * width + x] = sum;
      }
    for (int y = wanted.y_begin; y < wanted.y_end; ++y)
      for (int x = wanted.x_begin; x < wanted.x_end; ++x) {
        glm::dvec3 sum(0.0);
        for (int k = -radius; k <= radius; ++k) {
          const int row = std::clamp(y + k, 0, height - 1);
          sum += kernel[static_cast<size_t>(k + radius)] * rows[static_cast<size_t>(row) * width + x];
        }
        sense(static_cast<size_t>(y) * width + x, sum);
      }
  }

  // Ray through distorted pixel position (x - 0.5 + u, y - 0.5 + v), u, v in
  // [0, 1]: bilinear in the exact rays through the pixel's four corners. The
  // lens map bends by far less than a thousandth of a pixel across one pixel.
  glm::dvec3 rayInPixel(int x, int y, double u, double v, const FrameState& fs) const {
    const int stride = scene.camera.width_px + 1;
    auto corner = [&](int cx, int cy) {
      const float* r = &corner_rays_cam[(static_cast<size_t>(cy) * stride + cx) * 3];
      return glm::dvec3(r[0], r[1], r[2]);
    };
    glm::dvec3 top = glm::mix(corner(x, y), corner(x + 1, y), u);
    glm::dvec3 bottom = glm::mix(corner(x, y + 1), corner(x + 1, y + 1), u);
    return fs.world_from_cam * glm::normalize(glm::mix(top, bottom, v));
  }

  // Traces every pixel; emit(pixel_index, mean_radiance, objects) per pixel.
  //
  // A real sensor integrates light over each pixel's area. Regular point
  // samples do not: they put a straight edge's coverage in steps of 1/n, the
  // same step all along an edge that runs along the pixel grid, which biases
  // a fitted edge by up to 1/(2n) px. So every pixel whose corners or
  // samples see different edge classes (an edge crosses it: a straight line
  // through a square always separates two of its corners) is re-integrated
  // with n_edge x n_edge jittered (stratified) samples: unbiased, with a
  // coverage noise of about 0.3 / n_edge^1.5 px on a straight edge. Pixels
  // showing the ball are too (see below).
  //
  // The other pixels see one smooth surface (floor texture, sky). With
  // supersample_per_axis 0 (the default) such a pixel is the mean of the
  // radiance at its four corners, which the edge test traces anyway and
  // shares with its neighbours: the trapezoid rule, whose error for a smooth
  // texture is second order in the pixel size, as the regular grid's is. A
  // frame then costs about one ray a pixel plus the edge pixels' samples,
  // instead of n^2 + 1 a pixel. The post's pixels are integrated (below). A
  // curved outline that cuts a sliver off one side of a pixel without
  // reaching a corner is missed: a 30 px ball's arc strays at most
  // 1 / (8 * 30) px into such a pixel.
  //
  // With a window, only its pixels are traced and emitted (and the corners
  // around them): the rest of the frame costs nothing.
  template <typename Emit>
  void traceFrame(const FrameState& fs, const World::PixelWindow* window, Emit emit) const {
    const int width = scene.camera.width_px, height = scene.camera.height_px;
    const int x_begin = window ? std::clamp(window->x_begin, 0, width) : 0;
    const int x_end = window ? std::clamp(window->x_end, x_begin, width) : width;
    const int y_begin = window ? std::clamp(window->y_begin, 0, height) : 0;
    const int y_end = window ? std::clamp(window->y_end, y_begin, height) : height;
    const int threads = std::max(1, scene.render_threads);
    const int edge_n = scene.edge_samples_per_axis;
    const bool corner_rule = samples_per_pixel == 0;  // validate(): only with edge_n > 0
    std::vector<std::uint8_t> corner_class;
    std::vector<glm::dvec3> corner_radiance;
    std::vector<SceneObject> corner_object;
    if (edge_n > 0) {
      const size_t corners = static_cast<size_t>(width + 1) * (height + 1);
      corner_class.resize(corners);
      if (corner_rule) {
        corner_radiance.resize(corners);
        corner_object.resize(corners);
      }
      parallelRows(y_end + 1 - y_begin, threads, [&](int r0, int r1, int) {
        for (int y = y_begin + r0; y < y_begin + r1; ++y)
          for (int x = x_begin; x <= x_end; ++x) {
            const size_t i = static_cast<size_t>(y) * (width + 1) + x;
            const float* r = &corner_rays_cam[i * 3];
            const glm::dvec3 dir = fs.world_from_cam * glm::dvec3(r[0], r[1], r[2]);
            if (corner_rule)
              corner_radiance[i] = shadeCameraRay(dir, fs, corner_object[i], &corner_class[i]);
            else
              corner_class[i] = edgeClass(dir, fs);
          }
      });
    }
    parallelRows(y_end - y_begin, threads, [&](int r0, int r1, int) {
      std::vector<SceneObject> objects;
      for (int y = y_begin + r0; y < y_begin + r1; ++y)
        for (int x = x_begin; x < x_end; ++x) {
          const size_t pixel = static_cast<size_t>(y) * width + x;
          glm::dvec3 sum(0.0);
          const size_t c = static_cast<size_t>(y) * (width + 1) + x;
          const std::uint8_t k = edge_n > 0 ? corner_class[c] : 0;
          bool edge = edge_n > 0 && (corner_class[c + 1] != k || corner_class[c + width + 1] != k ||
                                     corner_class[c + width + 2] != k);
          bool shows_ball = false;
          if (corner_rule) {
            // The post is a few pixels wide: its shading turns through 180
            // degrees of normal across them, too fast for the trapezoid rule
            // (a corner mean strays f''/8 from the pixel's centre, 1% there),
            // so its pixels are integrated like the ball's.
            shows_ball = corner_object[c] == SceneObject::kProbe || corner_object[c] == SceneObject::kPost;
            if (!edge && !shows_ball) {
              objects.assign(4, corner_object[c]);
              emit(pixel,
                   0.25 * (corner_radiance[c] + corner_radiance[c + 1] + corner_radiance[c + width + 1] +
                           corner_radiance[c + width + 2]),
                   objects);
              continue;
            }
          } else {
            objects.resize(samples_per_pixel);
            for (int s = 0; s < samples_per_pixel; ++s) {
              std::uint8_t sample_class = k;
              sum += shadeCameraRay(cameraRay(pixel * samples_per_pixel + s, fs), fs, objects[s],
                                    edge_n > 0 ? &sample_class : nullptr);
              edge = edge || sample_class != k;
            }
            // The ball squeezes the whole environment into a few hundred
            // pixels: a sun's reflection there is far smaller than the
            // regular sub-sample spacing and would be hit or missed whole (a
            // factor of several in its energy). A sensor integrates over the
            // pixel, so ball pixels are integrated like edge pixels.
            shows_ball =
                edge_n > 0 && std::find(objects.begin(), objects.end(), SceneObject::kProbe) != objects.end();
          }
          if (edge || shows_ball) {
            // Jitter from the pixel index alone: the same frame renders the same bytes.
            objects.resize(static_cast<size_t>(edge_n) * edge_n);
            sum = glm::dvec3(0.0);
            for (int sy = 0; sy < edge_n; ++sy)
              for (int sx = 0; sx < edge_n; ++sx) {
                std::uint64_t bits = splitMix64(pixel * 1024u + static_cast<std::uint64_t>(sy * edge_n + sx));
                double u = (sx + (bits & 0xFFFF) / 65536.0) / edge_n;
                double v = (sy + ((bits >> 16) & 0xFFFF) / 65536.0) / edge_n;
                sum += shadeCameraRay(rayInPixel(x, y, u, v, fs), fs, objects[static_cast<size_t>(sy * edge_n + sx)],
                                      nullptr, 1.0 / static_cast<double>(edge_n * edge_n));
              }
            emit(pixel, sum / static_cast<double>(objects.size()), objects);
            continue;
          }
          emit(pixel, sum / static_cast<double>(samples_per_pixel), objects);
        }
    });
  }
};

namespace {

void validate(const SceneConfig& s) {
  auto require = [](bool ok, const std::string& message) {
    if (!ok) throw SceneError(message);
  };
  const auto& cam = s.camera;
  require(cam.width_px > 0 && cam.height_px > 0, "camera size must be positive, got " + std::to_string(cam.width_px) +
                                                     "x" + std::to_string(cam.height_px));
  require(cam.fx_px > 0 && cam.fy_px > 0, "camera focal lengths fx/fy must be positive");
  require(s.rig.probe_radius_m > 0, "rig.probe_radius must be positive");
  require(s.rig.probe_reflectance > 0 && s.rig.probe_reflectance <= 1,
          "rig.probe_reflectance must be in (0, 1], got " + std::to_string(s.rig.probe_reflectance));
  require(s.rig.probe_center_w.z > s.rig.probe_radius_m,
          "rig.probe_center z must exceed probe_radius (the ball must be above the ground)");
  for (auto [value, name] : {std::pair{s.tag_black_albedo, "tag_black_albedo"}, {s.tag_white_albedo, "tag_white_albedo"},
                             {s.floor_albedo, "floor_albedo"}, {s.post_albedo, "post_albedo"}})
    require(value >= 0 && value <= 1, std::string(name) + " must be in [0, 1], got " + std::to_string(value));
  require(s.supersample_per_axis >= 0 && s.supersample_per_axis <= 8, "supersample_per_axis must be 0..8");
  require(s.supersample_per_axis > 0 || s.edge_samples_per_axis > 0,
          "supersample_per_axis 0 (corner samples) needs edge_samples_per_axis above 0");
  require(s.edge_samples_per_axis >= 0 && s.edge_samples_per_axis <= 32, "edge_samples_per_axis must be 0..32");
  require(s.noise_sigma_code >= 0, "noise_sigma_code must not be negative");
  require(s.lens_blur_sigma_px >= 0 && s.lens_blur_sigma_px <= 16, "lens_blur_sigma_px must be 0..16");
  require(s.render_threads >= 1, "render_threads must be at least 1");
  require(s.auto_exposure || s.fixed_exposure > 0, "fixed_exposure must be positive");
  require(s.post_radius_m >= 0 && s.post_radius_m < s.rig.probe_radius_m, "post_radius_m must be in [0, probe_radius)");
}

}  // namespace

World::World(SceneConfig scene) {
  validate(scene);
  impl_ = std::make_unique<Impl>(scene);
  Impl& w = *impl_;
  w.environment = makeEnvironment(w.scene.environment);
  w.path = makeCameraPath(w.scene);
  w.tag = std::make_unique<TagPattern>(w.scene.rig.tag_family, w.scene.rig.tag_id, w.scene.rig.tag_size_m);

  const int threads = w.scene.render_threads;
  // Rotation-invariant lighting tables: environment at rotation 0, lamp alone.
  auto env_cells = upperHemisphereCells([&](const glm::dvec3& d) { return w.environment->radiance(d); }, threads);
  w.environment_irradiance_up = integrateCosine(env_cells, {0, 0, 1});
  if (!(luminance(w.environment_irradiance_up) > 0.0))
    throw SceneError("environment '" + w.scene.environment + "' sends no light from above");
  w.lamp_radiance = w.scene.lighting.lamp_relative_radiance * luminance(w.environment_irradiance_up) / kPi *
                    w.scene.lighting.lamp_colour;
  auto lamp_cells = upperHemisphereCells([&](const glm::dvec3& d) { return w.lampWeight(d) * w.lamp_radiance; }, threads);
  w.lamp_irradiance_up = integrateCosine(lamp_cells, {0, 0, 1});
  for (int i = 0; i < kPostAzimuthSteps; ++i) {
    double a = 2 * kPi * i / kPostAzimuthSteps;
    glm::dvec3 normal{std::cos(a), std::sin(a), 0.0};
    w.environment_irradiance_horizontal[i] = integrateCosine(env_cells, normal);
    w.lamp_irradiance_horizontal[i] = integrateCosine(lamp_cells, normal);
  }

  w.exposure = w.scene.auto_exposure
                   ? kAutoExposureTargetLinear /
                         (kAutoExposureWhiteAlbedo * luminance(w.irradianceUp(w.lightingAt(0))) / kPi)
                   : w.scene.fixed_exposure;

  // Sub-sample rays: an n x n regular grid inside each pixel (pixel centres at
  // integer coordinates, as OpenCV), undistorted once through OpenCV's model;
  // none for n = 0, where the pixel corners stand in (traceFrame).
  const auto& cam = w.scene.camera;
  const int n = w.scene.supersample_per_axis;
  w.samples_per_pixel = n * n;
  const size_t total = static_cast<size_t>(cam.width_px) * cam.height_px * w.samples_per_pixel;
  std::vector<cv::Point2f> distorted;
  const size_t corners = static_cast<size_t>(cam.width_px + 1) * (cam.height_px + 1);
  distorted.reserve(total + corners);
  for (int y = 0; y < cam.height_px; ++y)
    for (int x = 0; x < cam.width_px; ++x)
      for (int sy = 0; sy < n; ++sy)
        for (int sx = 0; sx < n; ++sx)
          distorted.emplace_back(static_cast<float>(x - 0.5 + (sx + 0.5) / n), static_cast<float>(y - 0.5 + (sy + 0.5) / n));
  // Then the pixel corners, for the edge pixels' area integration.
  for (int y = 0; y <= cam.height_px; ++y)
    for (int x = 0; x <= cam.width_px; ++x) distorted.emplace_back(static_cast<float>(x - 0.5), static_cast<float>(y - 0.5));
  cv::Matx33d k(cam.fx_px, 0, cam.cx_px, 0, cam.fy_px, cam.cy_px, 0, 0, 1);
  std::vector<double> distortion(cam.distortion.begin(), cam.distortion.end());
  std::vector<cv::Point2f> normalized;
  // More iterations than the default 5, so rays agree with cv::projectPoints
  // (the truth) to well under a hundredth of a pixel.
  cv::undistortPoints(distorted, normalized, k, distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 40, 1e-10));
  auto storeRays = [&](size_t first, size_t count, std::vector<float>& rays) {
    rays.resize(count * 3);
    for (size_t i = 0; i < count; ++i) {
      glm::dvec3 d = glm::normalize(glm::dvec3(normalized[first + i].x, normalized[first + i].y, 1.0));
      for (int c = 0; c < 3; ++c) rays[i * 3 + c] = static_cast<float>(d[c]);
    }
  };
  storeRays(0, total, w.rays_cam);
  storeRays(total, corners, w.corner_rays_cam);
  gaussianTable();  // build once here rather than inside the first render
}

World::~World() = default;

const SceneConfig& World::scene() const { return impl_->scene; }
PoseCamFromWorld World::pose(std::uint64_t frame_index) const { return impl_->path->pose(frame_index); }
double World::exposure() const { return impl_->exposure; }
LightingState World::lighting(std::uint64_t frame_index) const { return impl_->lightingAt(frame_index); }
glm::dvec3 World::postIrradiance(const glm::dvec3& normal_w, std::uint64_t frame_index) const {
  const Impl& w = *impl_;
  if (!(w.scene.post_albedo > 0.0)) return glm::dvec3(0.0);
  return kPi * w.exposure * Impl::postRadiance(w.frameState(frame_index), std::atan2(normal_w.y, normal_w.x)) /
         w.scene.post_albedo;
}

glm::dvec3 World::groundIrradianceUp(std::uint64_t frame_index) const {
  return impl_->irradianceUp(impl_->lightingAt(frame_index));
}

FrameTruth World::truth(std::uint64_t frame_index) const {
  const Impl& w = *impl_;
  FrameTruth truth;
  truth.pose = w.path->pose(frame_index);
  ProbeOutline outline = probeOutline(w.scene.camera, truth.pose, w.scene.rig.probe_center_w, w.scene.rig.probe_radius_m);
  truth.probe_center_px = outline.center_px;
  truth.probe_radius_px = outline.radius_px;
  truth.probe_fully_visible = outline.valid && outline.fully_visible;
  truth.exposure = w.exposure;
  truth.tag_fully_visible = tagFullyVisible(w.scene.camera, w.scene.rig, w.scene.post_radius_m, truth.pose);
  return truth;
}

void World::render(std::uint64_t frame_index, ImageRGB8& out, FrameTruth& truth, double exposure_ev,
                   const glm::dvec3& channel_gain, double shutter_frames) const {
  const Impl& w = *impl_;
  w.renderFrame(w.frameState(frame_index), frame_index, out, exposure_ev, nullptr, channel_gain, shutter_frames);
  truth = this->truth(frame_index);
}

std::vector<World::GroundShadowTruth> World::groundShadow(const std::vector<glm::dvec2>& ground_points_w,
                                                          const std::vector<VirtualOccluder>& occluders,
                                                          std::uint64_t frame_index) const {
  const Impl& w = *impl_;
  std::vector<GroundShadowTruth> result(ground_points_w.size());
  if (occluders.empty() || ground_points_w.empty()) return result;
  const ShadowContext context = w.shadowContext(w.lightingAt(frame_index), occluders);
  parallelRows(static_cast<int>(ground_points_w.size()), std::max(1, w.scene.render_threads), [&](int r0, int r1, int) {
    for (int i = r0; i < r1; ++i) result[static_cast<size_t>(i)] = w.shadowAt(ground_points_w[static_cast<size_t>(i)], context);
  });
  return result;
}

void World::renderWithOccluders(std::uint64_t frame_index, const std::vector<VirtualOccluder>& occluders,
                                ImageRGB8& out, FrameTruth& truth, const PixelWindow* window, const Lamp* lamp) const {
  const Impl& w = *impl_;
  FrameState fs = w.frameState(frame_index);
  const std::unique_ptr<OccluderFrame> occluder_frame = w.occluderFrame(fs, occluders);
  fs.occluders = occluder_frame.get();
  if (lamp != nullptr && lamp->intensity > 0.0) {
    fs.lamp = lamp;
    const glm::dvec3 e_up = w.irradianceUp(fs.lighting);
    const double y = 0.2126 * e_up.r + 0.7152 * e_up.g + 0.0722 * e_up.b;
    for (int c = 0; c < 3; ++c) fs.lamp_at_one_metre[c] = e_up[c] > 0.0 ? lamp->intensity * lamp->colour[c] * y / e_up[c] : 0.0;
  }
  fs.occluders_only = window && window->occluders_only;
  w.renderFrame(fs, frame_index, out, 0.0, window);
  truth = this->truth(frame_index);

  // The truth's visibility flags, now with the occluders in the way.
  auto hidden = [&](const glm::dvec3& target_w) {
    const glm::dvec3 to_target = target_w - fs.eye;
    const double distance_m = glm::length(to_target);
    for (const VirtualOccluder& occluder : occluders)
      if (auto t = intersectOccluder(occluder, fs.eye, to_target / distance_m); t && *t < distance_m - 1e-9) return true;
    return false;
  };
  if (truth.tag_fully_visible) {
    // The same kind of check as tagFullyVisible: a grid over the printed square.
    constexpr int kTagGrid = 21;
    const double half_m = 0.5 * w.scene.rig.tag_size_m;
    for (int i = 0; i < kTagGrid && truth.tag_fully_visible; ++i)
      for (int j = 0; j < kTagGrid && truth.tag_fully_visible; ++j)
        if (hidden({-half_m + 2.0 * half_m * i / (kTagGrid - 1), -half_m + 2.0 * half_m * j / (kTagGrid - 1), 0.0}))
          truth.tag_fully_visible = false;
  }
  if (truth.probe_fully_visible) {
    // The ball's outline: the circle where the tangent cone from the eye touches it.
    const glm::dvec3& center = w.scene.rig.probe_center_w;
    const double radius_m = w.scene.rig.probe_radius_m;
    const glm::dvec3 to_center = center - fs.eye;
    const double distance_m = glm::length(to_center);
    const glm::dvec3 axis = to_center / distance_m;
    const glm::dvec3 circle_center = center - (radius_m * radius_m / distance_m) * axis;
    const double circle_radius_m = radius_m * std::sqrt(1.0 - radius_m * radius_m / (distance_m * distance_m));
    const glm::dvec3 side = glm::normalize(glm::cross(axis, std::abs(axis.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0)));
    const glm::dvec3 up = glm::cross(axis, side);
    constexpr int kOutlinePoints = 72;
    for (int k = 0; k < kOutlinePoints && truth.probe_fully_visible; ++k) {
      const double a = 2.0 * kPi * k / kOutlinePoints;
      if (hidden(circle_center + circle_radius_m * (std::cos(a) * side + std::sin(a) * up))) truth.probe_fully_visible = false;
    }
  }
}

std::vector<float> World::coverage(std::uint64_t frame_index, SceneObject object) const {
  const Impl& w = *impl_;
  const FrameState fs = w.frameState(frame_index);
  std::vector<float> fraction(static_cast<size_t>(w.scene.camera.width_px) * w.scene.camera.height_px, 0.0f);
  w.traceFrame(fs, nullptr, [&](size_t pixel, const glm::dvec3&, const std::vector<SceneObject>& objects) {
    int hits = 0;
    for (SceneObject o : objects) hits += o == object ? 1 : 0;
    fraction[pixel] = static_cast<float>(hits) / static_cast<float>(objects.size());
  });
  return fraction;
}

IrradianceTruth World::irradiance(const glm::dvec3& normal_w, std::uint64_t frame_index) const {
  auto grid = impl_->truthGrid(impl_->lightingAt(frame_index));
  glm::dvec3 n = glm::normalize(normal_w);
  return {integrateCosine(grid->hdr, n), integrateCosine(grid->clipped, n)};
}

RadianceTruth World::radiance(const glm::dvec3& dir_w, std::uint64_t frame_index) const {
  const Impl& w = *impl_;
  glm::dvec3 camera_linear = w.exposure * w.ballCentreRadiance(glm::normalize(dir_w), w.lightingAt(frame_index));
  const double reflectance = w.scene.rig.probe_reflectance;
  return {camera_linear, glm::min(camera_linear * reflectance, glm::dvec3(1.0)) / reflectance};
}

}  // namespace probelight::sim
