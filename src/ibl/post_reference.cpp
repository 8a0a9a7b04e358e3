#include "ibl/post_reference.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include "core/math_constants.hpp"
#include "ibl/camera_projection.hpp"

namespace probelight::ibl {
namespace {

// Nearest hit (t > 0) of origin + t dir with the vertical cylinder of
// `radius` about axis_xy, between heights z_low and z_high.
std::optional<double> hitCylinder(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec2& axis_xy,
                                  double radius, double z_low, double z_high) {
  const glm::dvec2 o(origin.x - axis_xy.x, origin.y - axis_xy.y), d(dir.x, dir.y);
  const double a = glm::dot(d, d);
  if (a < 1e-18) return std::nullopt;
  const double b = glm::dot(o, d), c = glm::dot(o, o) - radius * radius;
  const double discriminant = b * b - a * c;
  if (discriminant < 0.0) return std::nullopt;
  const double t = (-b - std::sqrt(discriminant)) / a;  // the near side: the one facing the camera
  if (t <= 0.0) return std::nullopt;
  const double z = origin.z + t * dir.z;
  if (z < z_low || z > z_high) return std::nullopt;
  return t;
}

// The reading's cosine factor for light from `omega`: max(0, n . omega),
// averaged over the normals it was read at.
double meanCosine(const DiffuseReference& reference, const glm::dvec3& omega) {
  if (reference.pixel_normals_w.empty()) return std::max(0.0, glm::dot(reference.normal_w, omega));
  double sum = 0.0;
  for (const glm::dvec3& normal : reference.pixel_normals_w) sum += std::max(0.0, glm::dot(normal, omega));
  return sum / static_cast<double>(reference.pixel_normals_w.size());
}

std::optional<double> hitSphere(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec3& centre,
                                double radius) {
  const glm::dvec3 o = origin - centre;
  const double b = glm::dot(o, dir), c = glm::dot(o, o) - radius * radius;
  const double discriminant = b * b - c;  // dir is unit
  if (discriminant < 0.0) return std::nullopt;
  const double t = -b - std::sqrt(discriminant);
  if (t <= 0.0) return std::nullopt;
  return t;
}

}  // namespace

const char* toString(PostStatus status) {
  switch (status) {
    case PostStatus::kMeasured: return "measured";
    case PostStatus::kNoPost: return "no_post";
    case PostStatus::kNotInView: return "not_in_view";
    case PostStatus::kClipped: return "clipped";
    case PostStatus::kTooDark: return "too_dark";
  }
  return "unknown";
}

const char* toString(DiffuseFitStatus status) {
  switch (status) {
    case DiffuseFitStatus::kRefined: return "refined";
    case DiffuseFitStatus::kNothingToFit: return "nothing_to_fit";
    case DiffuseFitStatus::kInconsistent: return "inconsistent";
  }
  return "unknown";
}

DiffuseReference borderReference(const WhiteBorderReading& border, double tag_white_albedo) {
  return {{0.0, 0.0, 1.0}, kPi * border.linear_rgb / tag_white_albedo, border.patches_lit};
}

PostReading readPost(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const RigGeometry& rig,
                     const RgbPixelReader& read_pixel, const PostReadingSettings& settings) {
  PostReading reading;
  const double radius = rig.post_radius_m;
  const double top_z = rig.probe_center_w.z - rig.probe_radius_m;  // where the ball sits on it
  const double read_top_z = top_z - settings.min_distance_below_ball_radii * rig.probe_radius_m;
  if (!(radius > 0.0) || !(rig.post_albedo > 0.0)) {
    reading.message = "no post in rig.yaml (post_radius and post_albedo set it)";
    return reading;
  }
  if (!(read_top_z > 0.0)) {
    reading.message = "the post is too short: no part of it lies a ball radius below the ball";
    return reading;
  }
  const glm::dvec2 axis(rig.probe_center_w.x, rig.probe_center_w.y);
  const glm::dmat3 world_from_cam = glm::transpose(pose.R_cam_from_world);
  const glm::dvec3 eye = pose.cameraCenterWorld();
  // The pixels the read part of the post can cover: the box around it,
  // projected (points behind the camera leave the whole frame to search).
  double min_x = camera.width_px, min_y = camera.height_px, max_x = -1.0, max_y = -1.0;
  bool behind = false;
  for (const double z : {0.0, read_top_z})
    for (const double dx : {-radius, radius})
      for (const double dy : {-radius, radius}) {
        const glm::dvec3 p_cam = pose.toCamera({axis.x + dx, axis.y + dy, z});
        if (p_cam.z <= 1e-6) {
          behind = true;
          continue;
        }
        const glm::dvec2 pixel = projectToPixel(camera, p_cam);
        min_x = std::min(min_x, pixel.x), max_x = std::max(max_x, pixel.x);
        min_y = std::min(min_y, pixel.y), max_y = std::max(max_y, pixel.y);
      }
  if (behind) min_x = min_y = 0.0, max_x = camera.width_px - 1.0, max_y = camera.height_px - 1.0;
  const int x0 = std::max(0, static_cast<int>(std::floor(min_x)) - 1);
  const int x1 = std::min(camera.width_px - 1, static_cast<int>(std::ceil(max_x)) + 1);
  const int y0 = std::max(0, static_cast<int>(std::floor(min_y)) - 1);
  const int y1 = std::min(camera.height_px - 1, static_cast<int>(std::ceil(max_y)) + 1);
  // A ray's hit on the read part of the post, unless the ball is in front.
  auto hit = [&](const glm::dvec2& pixel) -> std::optional<glm::dvec3> {
    const glm::dvec3 dir = glm::normalize(world_from_cam * pixelToCameraRay(camera, pixel));
    const std::optional<double> t = hitCylinder(eye, dir, axis, radius, 0.0, read_top_z);
    if (!t) return std::nullopt;
    if (const std::optional<double> ball = hitSphere(eye, dir, rig.probe_center_w, rig.probe_radius_m); ball && *ball < *t)
      return std::nullopt;
    return eye + *t * dir;
  };
  const std::array<double, 256> decoded = [&] {
    std::array<double, 256> table{};
    for (int code = 0; code < 256; ++code)
      table[static_cast<std::size_t>(code)] = decodeCameraValue(settings.camera_transfer, code / 255.0);
    return table;
  }();
  struct Bin {
    std::vector<glm::dvec3> normals;
    glm::dvec3 normal_sum{0.0};
    glm::dvec3 linear_sum{0.0};
    int pixels = 0;
    bool clipped = false, dark = false;
  };
  std::map<int, Bin> bins;
  int pixels_partly = 0;  // centre on the post, a corner off it
  const double bin_width_rad = settings.bin_width_deg * kPi / 180.0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const std::optional<glm::dvec3> centre = hit(glm::dvec2(x, y));
      if (!centre) continue;
      bool whole = true;
      for (const glm::dvec2 corner : {glm::dvec2(-0.5, -0.5), glm::dvec2(0.5, -0.5), glm::dvec2(-0.5, 0.5), glm::dvec2(0.5, 0.5)})
        whole = whole && hit(glm::dvec2(x, y) + corner).has_value();
      if (!whole) {
        ++pixels_partly;
        continue;
      }
      ++reading.pixels_seen;
      const glm::dvec3 normal = glm::normalize(glm::dvec3(centre->x - axis.x, centre->y - axis.y, 0.0));
      const int key = static_cast<int>(std::floor(std::atan2(normal.y, normal.x) / bin_width_rad));
      Bin& bin = bins[key];
      const glm::u8vec3 code = read_pixel(x, y);
      const bool clipped = std::max({code.r, code.g, code.b}) >= settings.clip_code;
      const bool dark = !clipped && std::min({code.r, code.g, code.b}) <= settings.dark_code;
      reading.pixels_clipped += clipped ? 1 : 0;
      reading.pixels_dark += dark ? 1 : 0;
      bin.clipped = bin.clipped || clipped;
      bin.dark = bin.dark || dark;
      bin.normal_sum += normal;
      bin.normals.push_back(normal);
      bin.linear_sum += glm::dvec3(decoded[code.r], decoded[code.g], decoded[code.b]);
      ++bin.pixels;
    }
  int bins_clipped = 0, bins_dark = 0, bins_small = 0;
  for (const auto& [key, bin] : bins) {
    if (bin.pixels < settings.min_pixels_per_bin) {
      ++bins_small;
      continue;
    }
    if (bin.clipped || bin.dark) {
      bins_clipped += bin.clipped ? 1 : 0;
      bins_dark += (!bin.clipped && bin.dark) ? 1 : 0;
      continue;
    }
    reading.references.push_back({glm::normalize(bin.normal_sum), kPi * bin.linear_sum / (bin.pixels * rig.post_albedo),
                                  bin.pixels, bin.normals});
  }
  if (!reading.references.empty()) {
    reading.status = PostStatus::kMeasured;
    reading.message = "measured at " + std::to_string(reading.references.size()) + " normals from " +
                      std::to_string(reading.pixels_seen) + " pixels";
    if (bins_clipped + bins_dark > 0)
      reading.message += " (" + std::to_string(bins_clipped + bins_dark) + " bins left out, clipped or dark)";
  } else if (bins_clipped > 0) {
    reading.status = PostStatus::kClipped;
    reading.message = "the post is clipped (overexposed) wherever it is seen whole";
  } else if (bins_dark > 0) {
    reading.status = PostStatus::kTooDark;
    reading.message = "the post is black in the frame (covered, or underexposed)";
  } else {
    reading.status = PostStatus::kNotInView;
    reading.message = reading.pixels_seen == 0 && bins_small == 0 && pixels_partly == 0
                          ? "the post is not in view (out of the frame, or hidden)"
                          : "the post is too thin in the image: " + std::to_string(reading.pixels_seen) +
                                " pixels lie wholly on it";
  }
  return reading;
}

DiffuseFit fitClippedRegionsToReferences(CubeMapRGB& corrected, const CubeMapRGB& original,
                                         const std::vector<float>* validity, double clip_level,
                                         const std::vector<std::uint8_t>* clipped_mask,
                                         const std::vector<DiffuseReference>& references, int max_regions) {
  DiffuseFit fit;
  const std::vector<ClippedLight> regions =
      clippedLights(corrected, original, validity, clip_level, clipped_mask, max_regions);
  if (regions.empty() || references.empty()) {
    fit.message = regions.empty() ? "no light was added to clipped texels" : "no diffuse reference";
    return fit;
  }
  const int n = original.face_size;
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  const std::size_t rows = references.size(), columns = regions.size();
  // The 8-bit map's irradiance at each reference's normal, and each region's
  // added light there: a[row][region], per channel.
  std::vector<glm::dvec3> base(rows, glm::dvec3(0.0));
  std::vector<std::vector<glm::dvec3>> added(rows, std::vector<glm::dvec3>(columns, glm::dvec3(0.0)));
  std::vector<int> region_of(kCubeFaceCount * per_face, -1);
  for (std::size_t k = 0; k < columns; ++k)
    for (const std::uint32_t texel : regions[k].texels) region_of[texel] = static_cast<int>(k);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t index = static_cast<std::size_t>(y) * n + x;
        if (!texelSeen(validity, face, index, n)) continue;
        const glm::dvec3 omega = cubeTexelCenterDirection(face, x, y, n);
        const double solid_angle = cubeTexelSolidAngle(x, y, n);
        const glm::dvec3 seen(original.faces[face][index]);
        const int region = region_of[static_cast<std::size_t>(face) * per_face + index];
        const glm::dvec3 extra =
            region < 0 ? glm::dvec3(0.0) : glm::max(glm::dvec3(corrected.faces[face][index]) - seen, glm::dvec3(0.0));
        for (std::size_t j = 0; j < rows; ++j) {
          const double cosine = meanCosine(references[j], omega);
          if (cosine <= 0.0) continue;
          base[j] += seen * (cosine * solid_angle);
          if (region >= 0) added[j][static_cast<std::size_t>(region)] += extra * (cosine * solid_angle);
        }
      }
  for (const ClippedLight& region : regions) fit.region_direction_w.push_back(region.direction_w);
  for (std::size_t j = 0; j < rows; ++j)
    if (luminance(references[j].irradiance_rgb) < (1.0 - kReferenceDarkerTolerance) * luminance(base[j])) {
      fit.status = DiffuseFitStatus::kInconsistent;
      std::ostringstream facing;
      facing.setf(std::ios::fixed);
      facing.precision(2);
      facing << "(" << references[j].normal_w.x << ", " << references[j].normal_w.y << ", " << references[j].normal_w.z
             << ")";
      fit.message = "a reference facing " + facing.str() + " reads only " +
                    percentText(luminance(references[j].irradiance_rgb) / std::max(1e-30, luminance(base[j]))) +
                    " of the light the ball's unclipped part shows there (in shade, not matte, or its albedo set "
                    "too high): not used";
      fit.region_scale_rgb.assign(columns, glm::dvec3(1.0));
      return fit;
    }
  auto rmsRelative = [&](const std::vector<glm::dvec3>& scale) {
    double sum = 0.0;
    for (std::size_t j = 0; j < rows; ++j) {
      glm::dvec3 model = base[j];
      for (std::size_t k = 0; k < columns; ++k) model += scale[k] * added[j][k];
      const double wanted = luminance(references[j].irradiance_rgb);
      const double relative = (luminance(model) - wanted) / std::max(1e-30, wanted);
      sum += relative * relative;
    }
    return std::sqrt(sum / static_cast<double>(rows));
  };
  std::vector<glm::dvec3> scale(columns, glm::dvec3(1.0));
  fit.rms_relative_before = rmsRelative(scale);
  // Per channel: minimise sum_j ((base + sum_k a_jk s_k - E_j) / E_j)^2
  // + prior * sum_k (s_k - 1)^2 over s >= 0, by cyclic coordinate descent
  // (a convex quadratic with bounds: each step is the exact minimum along
  // one scale, so it converges; a few hundred sweeps of a 4-unknown problem
  // settle it far below any figure reported).
  for (int c = 0; c < 3; ++c) {
    std::vector<std::vector<double>> h(columns, std::vector<double>(columns, 0.0));
    std::vector<double> g(columns, 0.0);  // linear term: sum_j w a_jk (E_j - base_j)
    for (std::size_t j = 0; j < rows; ++j) {
      const double wanted = references[j].irradiance_rgb[c];
      const double weight = 1.0 / std::max(1e-30, wanted * wanted);
      for (std::size_t k = 0; k < columns; ++k) {
        g[k] += weight * added[j][k][c] * (wanted - base[j][c]);
        for (std::size_t l = 0; l < columns; ++l) h[k][l] += weight * added[j][k][c] * added[j][l][c];
      }
    }
    for (std::size_t k = 0; k < columns; ++k) {
      h[k][k] += kRegionScalePrior;
      g[k] += kRegionScalePrior;
    }
    std::vector<double> s(columns, 1.0);
    for (int sweep = 0; sweep < 500; ++sweep)
      for (std::size_t k = 0; k < columns; ++k) {
        double rest = g[k];
        for (std::size_t l = 0; l < columns; ++l)
          if (l != k) rest -= h[k][l] * s[l];
        s[k] = std::max(0.0, rest / h[k][k]);
      }
    for (std::size_t k = 0; k < columns; ++k) scale[k][c] = s[k];
  }
  fit.rms_relative_after = rmsRelative(scale);
  fit.region_scale_rgb = scale;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (std::size_t index = 0; index < per_face; ++index) {
      const int region = region_of[static_cast<std::size_t>(face) * per_face + index];
      if (region < 0) continue;
      const glm::dvec3 seen(original.faces[face][index]);
      const glm::dvec3 extra = glm::max(glm::dvec3(corrected.faces[face][index]) - seen, glm::dvec3(0.0));
      corrected.faces[face][index] = glm::vec3(seen + scale[static_cast<std::size_t>(region)] * extra);
    }
  fit.status = DiffuseFitStatus::kRefined;
  fit.message = "the clipped light divided between " + std::to_string(columns) + " regions by " +
                std::to_string(rows) + " diffuse readings: they disagree with the map by " +
                percentText(fit.rms_relative_before) + " (rms) with the border's equal share, " +
                percentText(fit.rms_relative_after) + " after";
  return fit;
}

PostCorrection correctClippedWithPost(CubeMapRGB& corrected, const CubeMapRGB& original,
                                      const std::vector<float>* validity, double clip_level,
                                      const std::vector<std::uint8_t>* clipped_mask, const WhiteBorderReading& border,
                                      const RigGeometry& rig, const CameraIntrinsics& camera,
                                      const PoseCamFromWorld& pose, const RgbPixelReader& read_pixel,
                                      const PostReadingSettings& settings) {
  PostCorrection correction;
  correction.reading = readPost(camera, pose, rig, read_pixel, settings);
  if (correction.reading.status != PostStatus::kMeasured) {
    correction.fit.message = "the post was not read: " + correction.reading.message;
    return correction;
  }
  std::vector<DiffuseReference> references = {borderReference(border, rig.tag_white_albedo)};
  references.insert(references.end(), correction.reading.references.begin(), correction.reading.references.end());
  correction.fit =
      fitClippedRegionsToReferences(corrected, original, validity, clip_level, clipped_mask, references);
  return correction;
}

}  // namespace probelight::ibl
