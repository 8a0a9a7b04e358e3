#include "sim/world.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <thread>

#include <opencv2/calib3d.hpp>

#include "sim/camera_path.hpp"
#include "sim/environment.hpp"
#include "sim/scene_geometry.hpp"
#include "sim/tag_pattern.hpp"

namespace probelight::sim {
namespace {

constexpr double kPi = std::numbers::pi;
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

double degToRad(double deg) { return deg * kPi / 180.0; }

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

// 65536 equal-probability standard-normal values: a 16-bit hash picks one.
const std::vector<float>& gaussianTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (int i = 0; i < 65536; ++i) t[i] = static_cast<float>(normalQuantile((i + 0.5) / 65536.0));
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
  // Interleaved blocks balance rows with and without the ball.
  constexpr int kBlock = 8;
  if (threads <= 1) {
    fn(0, rows, 1);
    return;
  }
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([=] {
      for (int start = t * kBlock; start < rows; start += threads * kBlock) fn(start, std::min(rows, start + kBlock), 1);
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
// so it never looks like a tag to the detector.
double valueNoise(double x, double y, std::uint64_t salt) {
  double fx = std::floor(x), fy = std::floor(y);
  auto lattice = [&](double ix, double iy) {
    std::uint64_t h = splitMix64(salt ^ splitMix64(static_cast<std::uint64_t>(static_cast<std::int64_t>(ix)) * 73856093ull ^
                                                   static_cast<std::uint64_t>(static_cast<std::int64_t>(iy)) * 19349663ull));
    return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53) * 2.0 - 1.0;
  };
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  double a = lattice(fx, fy), b = lattice(fx + 1, fy), c = lattice(fx, fy + 1), d = lattice(fx + 1, fy + 1);
  return (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty;
}

struct FrameState {
  PoseCamFromWorld pose;
  glm::dmat3 world_from_cam;
  glm::dvec3 eye;
  LightingState lighting;
  glm::dvec3 ground_radiance_per_albedo;              // E_up / pi
  std::array<glm::dvec3, kPostAzimuthSteps> post_radiance;  // by world azimuth of the post's normal
};

struct TruthGrid {
  std::vector<glm::dvec3> hdr;      // camera linear units
  std::vector<glm::dvec3> clipped;  // camera linear units, reflectance undone
};

}  // namespace

struct World::Impl {
  SceneConfig scene;
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
    double texture = 0.65 * valueNoise(x / 0.09, y / 0.09, scene.seed) + 0.35 * valueNoise(x / 0.027, y / 0.027, scene.seed + 7);
    return std::clamp(scene.floor_albedo * (1.0 + scene.floor_texture_contrast * texture), 0.0, 1.0);
  }

  FrameState frameState(std::uint64_t frame) const {
    FrameState fs;
    fs.pose = path->pose(frame);
    fs.world_from_cam = glm::transpose(fs.pose.R_cam_from_world);
    fs.eye = fs.pose.cameraCenterWorld();
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

  // The first object a camera ray hits, and the distance to it (+inf for the environment).
  double firstHit(const glm::dvec3& dir, const FrameState& fs, SceneObject& object) const {
    const RigGeometry& rig = scene.rig;
    double t_best = std::numeric_limits<double>::infinity();
    object = SceneObject::kEnvironment;
    if (auto t = intersectSphere(fs.eye, dir, rig.probe_center_w, rig.probe_radius_m)) {
      t_best = *t;
      object = SceneObject::kProbe;
    }
    if (auto t = intersectPost(fs.eye, dir, {rig.probe_center_w.x, rig.probe_center_w.y}, scene.post_radius_m,
                               rig.probe_center_w.z - rig.probe_radius_m);
        t && *t < t_best) {
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
    return t_best;
  }

  // What a pixel edge can separate: the object, and on the tag its cell's
  // colour. Floor texture, sky and the ball's reflection vary smoothly
  // enough at the pixel scale for regular sub-samples.
  std::uint8_t edgeClass(const glm::dvec3& dir, const FrameState& fs) const {
    SceneObject object;
    double t = firstHit(dir, fs, object);
    bool white = false;
    if (object == SceneObject::kFloor) {
      glm::dvec3 p = fs.eye + t * dir;
      groundAlbedo(p.x, p.y, object, &white);
    }
    return classOf(object, white);
  }

  static std::uint8_t classOf(SceneObject object, bool tag_white) {
    return static_cast<std::uint8_t>(static_cast<int>(object) | (tag_white ? 8 : 0));
  }

  // Scene radiance along a camera ray, and the first object it hits (and, when
  // asked, its edgeClass, for free).
  glm::dvec3 shadeCameraRay(const glm::dvec3& dir, const FrameState& fs, SceneObject& object,
                            std::uint8_t* edge_class = nullptr) const {
    bool white = false;
    glm::dvec3 radiance = shadeHit(dir, fs, firstHit(dir, fs, object), object, white);
    if (edge_class) *edge_class = classOf(object, white);
    return radiance;
  }

  // Radiance of the first hit at distance t_best along dir; `object` floor
  // becomes tag where the tag is printed.
  glm::dvec3 shadeHit(const glm::dvec3& dir, const FrameState& fs, double t_best, SceneObject& object,
                      bool& white) const {
    const RigGeometry& rig = scene.rig;
    switch (object) {
      case SceneObject::kEnvironment:
        return environmentRadiance(dir, fs.lighting);
      case SceneObject::kFloor:
      case SceneObject::kTag:
        return groundRadiance(fs.eye + t_best * dir, fs, object, &white);
      case SceneObject::kPost: {
        glm::dvec3 p = fs.eye + t_best * dir;
        double azimuth = std::atan2(p.y - rig.probe_center_w.y, p.x - rig.probe_center_w.x);
        double x = azimuth / (2 * kPi) * kPostAzimuthSteps;
        x -= std::floor(x / kPostAzimuthSteps) * kPostAzimuthSteps;
        int i0 = static_cast<int>(x) % kPostAzimuthSteps;
        double f = x - std::floor(x);
        return (1 - f) * fs.post_radiance[i0] + f * fs.post_radiance[(i0 + 1) % kPostAzimuthSteps];
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
  // coverage noise of about 0.3 / n_edge^1.5 px on a straight edge.
  template <typename Emit>
  void traceFrame(const FrameState& fs, Emit emit) const {
    const int width = scene.camera.width_px, height = scene.camera.height_px;
    const int threads = std::max(1, scene.render_threads);
    const int edge_n = scene.edge_samples_per_axis;
    std::vector<std::uint8_t> corner_class;
    if (edge_n > 0) {
      corner_class.resize(static_cast<size_t>(width + 1) * (height + 1));
      parallelRows(height + 1, threads, [&](int r0, int r1, int) {
        for (int y = r0; y < r1; ++y)
          for (int x = 0; x <= width; ++x) {
            const size_t i = static_cast<size_t>(y) * (width + 1) + x;
            const float* r = &corner_rays_cam[i * 3];
            corner_class[i] = edgeClass(fs.world_from_cam * glm::dvec3(r[0], r[1], r[2]), fs);
          }
      });
    }
    parallelRows(height, threads, [&](int r0, int r1, int) {
      std::vector<SceneObject> objects;
      for (int y = r0; y < r1; ++y)
        for (int x = 0; x < width; ++x) {
          const size_t pixel = static_cast<size_t>(y) * width + x;
          glm::dvec3 sum(0.0);
          objects.resize(samples_per_pixel);
          const size_t c = static_cast<size_t>(y) * (width + 1) + x;
          const std::uint8_t k = edge_n > 0 ? corner_class[c] : 0;
          bool edge = edge_n > 0 && (corner_class[c + 1] != k || corner_class[c + width + 1] != k ||
                                     corner_class[c + width + 2] != k);
          for (int s = 0; s < samples_per_pixel; ++s) {
            std::uint8_t sample_class = k;
            sum += shadeCameraRay(cameraRay(pixel * samples_per_pixel + s, fs), fs, objects[s],
                                  edge_n > 0 ? &sample_class : nullptr);
            edge = edge || sample_class != k;
          }
          if (edge) {
            // Jitter from the pixel index alone: the same frame renders the same bytes.
            objects.resize(static_cast<size_t>(edge_n) * edge_n);
            sum = glm::dvec3(0.0);
            for (int sy = 0; sy < edge_n; ++sy)
              for (int sx = 0; sx < edge_n; ++sx) {
                std::uint64_t bits = splitMix64(pixel * 1024u + static_cast<std::uint64_t>(sy * edge_n + sx));
                double u = (sx + (bits & 0xFFFF) / 65536.0) / edge_n;
                double v = (sy + ((bits >> 16) & 0xFFFF) / 65536.0) / edge_n;
                sum += shadeCameraRay(rayInPixel(x, y, u, v, fs), fs, objects[static_cast<size_t>(sy * edge_n + sx)]);
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
  require(s.supersample_per_axis >= 1 && s.supersample_per_axis <= 8, "supersample_per_axis must be 1..8");
  require(s.edge_samples_per_axis >= 0 && s.edge_samples_per_axis <= 32, "edge_samples_per_axis must be 0..32");
  require(s.noise_sigma_code >= 0, "noise_sigma_code must not be negative");
  require(s.render_threads >= 1, "render_threads must be at least 1");
  require(s.auto_exposure || s.fixed_exposure > 0, "fixed_exposure must be positive");
  require(s.post_radius_m >= 0 && s.post_radius_m < s.rig.probe_radius_m, "post_radius_m must be in [0, probe_radius)");
}

}  // namespace

World::World(SceneConfig scene) : impl_(std::make_unique<Impl>()) {
  validate(scene);
  Impl& w = *impl_;
  w.scene = std::move(scene);
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
  // integer coordinates, as OpenCV), undistorted once through OpenCV's model.
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

void World::render(std::uint64_t frame_index, ImageRGB8& out, FrameTruth& truth) const {
  const Impl& w = *impl_;
  const FrameState fs = w.frameState(frame_index);
  out.resize(w.scene.camera.width_px, w.scene.camera.height_px);
  const double scale = w.exposure;
  const float sigma = static_cast<float>(w.scene.noise_sigma_code);
  const std::vector<float>& gaussian = gaussianTable();
  const std::uint64_t frame_salt = splitMix64(w.scene.seed ^ splitMix64(frame_index));
  std::uint8_t* pixels = out.pixels.data();
  w.traceFrame(fs, [&](size_t pixel, const glm::dvec3& sum, const std::vector<SceneObject>&) {
    // Noise is a function of (seed, frame, pixel) only, so threads and
    // render order cannot change it.
    std::uint64_t bits = splitMix64(frame_salt + pixel);
    for (int c = 0; c < 3; ++c) {
      float code = w.srgb.encode(sum[c] * scale);
      if (sigma > 0.0f) code += sigma * gaussian[(bits >> (16 * c)) & 0xFFFF];
      pixels[pixel * 3 + c] = static_cast<std::uint8_t>(std::clamp(std::lround(code), 0L, 255L));
    }
  });
  truth = this->truth(frame_index);
}

std::vector<float> World::coverage(std::uint64_t frame_index, SceneObject object) const {
  const Impl& w = *impl_;
  const FrameState fs = w.frameState(frame_index);
  std::vector<float> fraction(static_cast<size_t>(w.scene.camera.width_px) * w.scene.camera.height_px, 0.0f);
  w.traceFrame(fs, [&](size_t pixel, const glm::dvec3&, const std::vector<SceneObject>& objects) {
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
