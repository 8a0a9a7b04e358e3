#include "ibl/white_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/math_constants.hpp"
#include "ibl/camera_projection.hpp"
#include "ibl/probe_outline.hpp"

namespace probelight::ibl {

std::string percentText(double fraction) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(0);
  out << 100.0 * fraction << "%";
  return out.str();
}

WhiteRing tagWhiteRing(int width_at_border_cells, bool reversed_border, double tag_size_m) {
  const double half = tag_size_m / 2.0;
  const double cell = tag_size_m / width_at_border_cells;
  return reversed_border ? WhiteRing{half - cell, half} : WhiteRing{half, half + cell};
}

const char* toString(WhiteBorderStatus status) {
  switch (status) {
    case WhiteBorderStatus::kMeasured: return "measured";
    case WhiteBorderStatus::kNotInView: return "not_in_view";
    case WhiteBorderStatus::kTooSmall: return "too_small";
    case WhiteBorderStatus::kClipped: return "clipped";
    case WhiteBorderStatus::kTooDark: return "too_dark";
  }
  return "unknown";
}

const char* toString(WhiteReferenceStatus status) {
  switch (status) {
    case WhiteReferenceStatus::kCorrected: return "corrected";
    case WhiteReferenceStatus::kNothingClipped: return "nothing_clipped";
    case WhiteReferenceStatus::kNoShortfall: return "no_shortfall";
    case WhiteReferenceStatus::kBorderDarker: return "border_darker";
    case WhiteReferenceStatus::kBorderUnusable: return "border_unusable";
  }
  return "unknown";
}

WhiteBorderReading readWhiteBorder(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, const WhiteRing& ring,
                                   const RgbPixelReader& read_pixel, const WhiteBorderSettings& settings) {
  WhiteBorderReading reading;
  const double width_m = ring.outer_half_m - ring.inner_half_m;
  // The middle half of the ring's width.
  const double across0 = ring.inner_half_m + 0.25 * width_m, across1 = ring.outer_half_m - 0.25 * width_m;
  // A point on side `side` (0: +X, 1: +Y, 2: -X, 3: -Y) at distance
  // `across` from the centre and `along` along the side.
  auto pointOnSide = [](int side, double across, double along) {
    switch (side) {
      case 0: return glm::dvec3(across, along, 0.0);
      case 1: return glm::dvec3(-along, across, 0.0);
      case 2: return glm::dvec3(-across, -along, 0.0);
      default: return glm::dvec3(along, -across, 0.0);
    }
  };
  auto toPixel = [&](const glm::dvec3& point_w, glm::dvec2& pixel) {
    const glm::dvec3 point_cam = pose.toCamera(point_w);
    if (point_cam.z <= 1e-6) return false;
    pixel = projectToPixel(camera, point_cam);
    return std::isfinite(pixel.x) && std::isfinite(pixel.y);
  };
  auto inFrame = [&](const glm::dvec2& pixel, int& x, int& y) {
    x = static_cast<int>(std::lround(pixel.x));
    y = static_cast<int>(std::lround(pixel.y));
    return x >= 0 && y >= 0 && x < camera.width_px && y < camera.height_px;
  };

  // Corners of the ring (where two sides' bands overlap) left out, and a
  // little more: the black border's corners are where pose error shows most.
  const double along_half = 0.95 * ring.inner_half_m;
  const int patches_per_side = std::max(1, settings.patches_per_side);
  const double clip_linear = decodeCameraValue(settings.camera_transfer, settings.clip_code / 255.0);
  struct Patch {
    glm::dvec3 linear{0.0};
    bool clipped = false;
    bool dark = false;
  };
  std::vector<Patch> patches;
  reading.sampled_width_px = std::numeric_limits<double>::infinity();
  for (int side = 0; side < 4; ++side) {
    glm::dvec2 a, b;
    if (toPixel(pointOnSide(side, across0, 0.0), a) && toPixel(pointOnSide(side, across1, 0.0), b))
      reading.sampled_width_px = std::min(reading.sampled_width_px, glm::length(b - a));
    for (int p = 0; p < patches_per_side; ++p) {
      const double along0 = -along_half + 2.0 * along_half * p / patches_per_side;
      const double along1 = -along_half + 2.0 * along_half * (p + 1) / patches_per_side;
      glm::dvec2 c0, c1, c2;
      if (!toPixel(pointOnSide(side, across0, along0), c0) || !toPixel(pointOnSide(side, across0, along1), c1) ||
          !toPixel(pointOnSide(side, across1, along0), c2))
        continue;
      // About one sample a pixel in each direction, at least 2 x 2.
      const int n_along = std::clamp(static_cast<int>(std::ceil(glm::length(c1 - c0))), 2, 256);
      const int n_across = std::clamp(static_cast<int>(std::ceil(glm::length(c2 - c0))), 2, 64);
      int inside = 0, clipped_samples = 0;
      glm::dvec3 sum(0.0), code_sum(0.0);
      for (int i = 0; i < n_along; ++i)
        for (int j = 0; j < n_across; ++j) {
          const double along = along0 + (along1 - along0) * (i + 0.5) / n_along;
          const double across = across0 + (across1 - across0) * (j + 0.5) / n_across;
          glm::dvec2 pixel;
          int x = 0, y = 0;
          if (!toPixel(pointOnSide(side, across, along), pixel) || !inFrame(pixel, x, y)) continue;
          const glm::u8vec3 code = read_pixel(x, y);
          ++inside;
          if (std::max({code.r, code.g, code.b}) >= settings.clip_code) ++clipped_samples;
          code_sum += glm::dvec3(code);
          for (int c = 0; c < 3; ++c) sum[c] += decodeCameraValue(settings.camera_transfer, code[c] / 255.0);
        }
      // A patch partly outside the frame is left out whole: its inside part
      // may be a sliver at the edge.
      if (inside < (9 * n_along * n_across) / 10) continue;
      Patch patch;
      patch.linear = sum / static_cast<double>(inside);
      // Noise (a code or two) lifts some samples of a border just under the
      // clip over it; a quarter of them clipped means the patch is.
      patch.clipped = 4 * clipped_samples > inside ||
                      std::max({patch.linear.r, patch.linear.g, patch.linear.b}) >= clip_linear;
      const glm::dvec3 mean_code = code_sum / static_cast<double>(inside);
      patch.dark = std::min({mean_code.r, mean_code.g, mean_code.b}) <= settings.dark_code;
      patches.push_back(patch);
    }
  }
  reading.patches = static_cast<int>(patches.size());
  if (patches.empty()) {
    reading.status = WhiteBorderStatus::kNotInView;
    reading.message = "the tag's white border is not in the frame";
    reading.sampled_width_px = 0.0;
    return reading;
  }
  if (reading.sampled_width_px < settings.min_sampled_width_px) {
    reading.status = WhiteBorderStatus::kTooSmall;
    std::ostringstream out;
    out.precision(2);
    out << "the tag's white border is " << 2.0 * reading.sampled_width_px << " px wide in the image: too small to read";
    reading.message = out.str();
    return reading;
  }
  std::vector<double> lit_levels;
  for (const Patch& patch : patches) {
    reading.patches_clipped += patch.clipped ? 1 : 0;
    reading.patches_dark += (!patch.clipped && patch.dark) ? 1 : 0;
    if (!patch.clipped && !patch.dark) lit_levels.push_back(luminance(patch.linear));
  }
  if (reading.patches_clipped > 0) {
    // Part of the border clipped: its lit level is only bounded below (and
    // any unclipped patch may be the shaded part).
    reading.status = WhiteBorderStatus::kClipped;
    reading.message = "the tag's white border is clipped in " + std::to_string(reading.patches_clipped) + " of " +
                      std::to_string(reading.patches) + " patches (overexposed)";
    return reading;
  }
  if (lit_levels.empty()) {
    reading.status = WhiteBorderStatus::kTooDark;
    reading.message = "the tag's white border is black in the frame (covered, or underexposed)";
    return reading;
  }
  // The lit level: the upper quartile of the patches, so up to three
  // quarters of the border may lie in a shadow.
  std::sort(lit_levels.begin(), lit_levels.end());
  const double lit_level = lit_levels[(3 * (lit_levels.size() - 1) + 2) / 4];
  glm::dvec3 sum(0.0);
  for (const Patch& patch : patches) {
    if (patch.clipped || patch.dark) continue;
    if (luminance(patch.linear) < settings.shadow_fraction * lit_level) {
      ++reading.patches_shadowed;
      continue;
    }
    sum += patch.linear;
    ++reading.patches_lit;
  }
  reading.linear_rgb = sum / static_cast<double>(reading.patches_lit);
  reading.status = WhiteBorderStatus::kMeasured;
  reading.message = "measured in " + std::to_string(reading.patches_lit) + " of " + std::to_string(reading.patches) +
                    " patches" +
                    (reading.patches_shadowed > 0 ? " (" + std::to_string(reading.patches_shadowed) + " in shadow, left out)"
                                                  : std::string());
  return reading;
}

std::vector<std::uint8_t> clippedTexelMask(const MirrorBallView& view, const RgbPixelReader& read_pixel, int clip_code,
                                           int face_size) {
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(kCubeFaceCount) * face_size * face_size, 0);
  const ProbeOutline outline = computeProbeOutline(view);
  if (!outline.valid) return mask;
  const int x0 = std::max(0, static_cast<int>(std::floor(outline.min_px.x)));
  const int x1 = std::min(view.camera.width_px - 1, static_cast<int>(std::ceil(outline.max_px.x)));
  const int y0 = std::max(0, static_cast<int>(std::floor(outline.min_px.y)));
  const int y1 = std::min(view.camera.height_px - 1, static_cast<int>(std::ceil(outline.max_px.y)));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const glm::u8vec3 code = read_pixel(x, y);
      if (std::max({code.r, code.g, code.b}) < clip_code) continue;
      const std::optional<glm::dvec3> direction = pixelToReflectedDirection(view, glm::dvec2(x, y));
      if (!direction) continue;
      const CubeTexelCoord coord = directionToCubeCoord(*direction);
      const int tx = std::clamp(static_cast<int>(coord.s * face_size), 0, face_size - 1);
      const int ty = std::clamp(static_cast<int>(coord.t * face_size), 0, face_size - 1);
      mask[static_cast<std::size_t>(coord.face) * face_size * face_size + static_cast<std::size_t>(ty) * face_size + tx] = 1;
    }
  return mask;
}

namespace {
bool maskSays(const std::vector<std::uint8_t>* mask, int face, std::size_t index, int face_size) {
  const std::size_t per_face = static_cast<std::size_t>(face_size) * face_size;
  return mask != nullptr && mask->size() == kCubeFaceCount * per_face &&
         (*mask)[static_cast<std::size_t>(face) * per_face + index] != 0;
}
}  // namespace

WhiteReferenceResult correctClippedWithWhiteBorder(CubeMapRGB& map, const std::vector<float>* validity,
                                                   const WhiteBorderReading& border, double tag_white_albedo,
                                                   double clip_level, const std::vector<std::uint8_t>* clipped_mask) {
  WhiteReferenceResult result;
  const int n = map.face_size;
  glm::dvec3 e_map(0.0);
  double cosine_weight_clipped = 0.0;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t index = static_cast<std::size_t>(y) * n + x;
        if (!texelSeen(validity, face, index, n)) continue;
        const glm::dvec3 omega = cubeTexelCenterDirection(face, x, y, n);
        const double solid_angle = cubeTexelSolidAngle(x, y, n);
        const glm::vec3& radiance = map.faces[face][index];
        const bool clipped = std::max({radiance.r, radiance.g, radiance.b}) >= clip_level ||
                             maskSays(clipped_mask, face, index, n);
        if (omega.z > 0.0) {
          e_map += glm::dvec3(radiance) * omega.z * solid_angle;
          if (clipped) {
            result.clipped_upper_sr += solid_angle;
            cosine_weight_clipped += omega.z * solid_angle;
          }
        } else if (clipped) {
          result.clipped_lower_sr += solid_angle;
        }
      }
  result.map_irradiance_rgb = e_map;
  if (border.status != WhiteBorderStatus::kMeasured) {
    result.status = WhiteReferenceStatus::kBorderUnusable;
    result.message = border.message;
    return result;
  }
  result.border_irradiance_rgb = kPi * border.linear_rgb / tag_white_albedo;
  const double ratio = luminance(result.border_irradiance_rgb) / std::max(1e-30, luminance(e_map));
  if (cosine_weight_clipped <= 0.0) {
    result.status = WhiteReferenceStatus::kNothingClipped;
    result.message = "nothing clipped above the horizon; the border reads " + percentText(ratio) +
                     " of the ball's irradiance";
    return result;
  }
  if (ratio < 1.0 - kBorderDarkerTolerance) {
    result.status = WhiteReferenceStatus::kBorderDarker;
    result.message = "the border reads only " + percentText(ratio) +
                     " of the irradiance the ball shows (in shadow, printed without its white margin, or "
                     "tag_white_albedo too high): not used";
    return result;
  }
  const glm::dvec3 shortfall = glm::max(result.border_irradiance_rgb - e_map, glm::dvec3(0.0));
  if (luminance(shortfall) <= 0.0) {
    result.status = WhiteReferenceStatus::kNoShortfall;
    result.message = "the border reads " + percentText(ratio) + " of the ball's irradiance: nothing missing";
    return result;
  }
  result.added_radiance_rgb = shortfall / cosine_weight_clipped;
  const glm::vec3 added(result.added_radiance_rgb);
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t index = static_cast<std::size_t>(y) * n + x;
        if (!texelSeen(validity, face, index, n) || cubeTexelCenterDirection(face, x, y, n).z <= 0.0) continue;
        glm::vec3& radiance = map.faces[face][index];
        if (std::max({radiance.r, radiance.g, radiance.b}) >= clip_level || maskSays(clipped_mask, face, index, n))
          radiance += added;
      }
  result.status = WhiteReferenceStatus::kCorrected;
  result.message = "the border reads " + percentText(ratio) + " of the ball's irradiance; the rest given to " +
                   percentText(result.clipped_upper_sr / (2.0 * kPi)) + " of the sky that clipped";
  return result;
}

std::vector<ClippedLight> clippedLights(const CubeMapRGB& true_map, const CubeMapRGB& clipped_map,
                                        const std::vector<float>* validity, double clip_level,
                                        const std::vector<std::uint8_t>* clipped_mask, int max_lights,
                                        double cluster_radius_rad) {
  struct Texel {
    glm::dvec3 omega;
    glm::dvec3 energy_rgb;  // extra radiance times solid angle
    double energy = 0.0;
    std::uint32_t index = 0;  // face * n^2 + y * n + x
  };
  std::vector<Texel> texels;
  const int n = clipped_map.face_size;
  for (int face = 0; face < kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const std::size_t index = static_cast<std::size_t>(y) * n + x;
        if (!texelSeen(validity, face, index, n)) continue;
        const glm::vec3& seen = clipped_map.faces[face][index];
        const glm::vec3& real = true_map.faces[face][index];
        // Where the truth is beyond the clip, the 8-bit map's value there
        // (clipped, or a sun smeared over a texel) is not the light.
        if (std::max({seen.r, seen.g, seen.b}) < clip_level && std::max({real.r, real.g, real.b}) < clip_level &&
            !maskSays(clipped_mask, face, index, n))
          continue;
        const glm::dvec3 extra = glm::max(glm::dvec3(real) - glm::dvec3(seen), glm::dvec3(0.0));
        const double solid_angle = cubeTexelSolidAngle(x, y, n);
        Texel texel{cubeTexelCenterDirection(face, x, y, n), extra * solid_angle, luminance(extra) * solid_angle,
                    static_cast<std::uint32_t>(face * n * n + y * n + x)};
        if (texel.energy > 0.0) texels.push_back(texel);
      }
  std::sort(texels.begin(), texels.end(), [](const Texel& a, const Texel& b) { return a.energy > b.energy; });
  struct Cluster {
    glm::dvec3 seed;
    glm::dmat3 moment{0.0};  // column c: sum of energy_rgb[c] * omega
    std::vector<const Texel*> members;
  };
  std::vector<Cluster> clusters;
  const double cos_radius = std::cos(cluster_radius_rad);
  for (const Texel& texel : texels) {
    Cluster* home = nullptr;
    for (Cluster& cluster : clusters)
      if (glm::dot(cluster.seed, texel.omega) >= cos_radius) {
        home = &cluster;
        break;
      }
    if (home == nullptr) {
      clusters.push_back({texel.omega});
      home = &clusters.back();
    }
    for (int c = 0; c < 3; ++c) home->moment[c] += texel.energy_rgb[c] * texel.omega;
    home->members.push_back(&texel);
  }
  // Beyond max_lights, the faintest clusters join the nearest kept one (a
  // first moment adds).
  auto momentEnergy = [](const Cluster& cluster) {
    return glm::length(luminanceWeighted(cluster.moment[0], cluster.moment[1], cluster.moment[2]));
  };
  std::sort(clusters.begin(), clusters.end(),
            [&](const Cluster& a, const Cluster& b) { return momentEnergy(a) > momentEnergy(b); });
  const std::size_t kept = std::min(clusters.size(), static_cast<std::size_t>(std::max(0, max_lights)));
  for (std::size_t extra = kept; extra < clusters.size() && kept > 0; ++extra) {
    std::size_t nearest = 0;
    for (std::size_t k = 1; k < kept; ++k)
      if (glm::dot(clusters[k].seed, clusters[extra].seed) > glm::dot(clusters[nearest].seed, clusters[extra].seed))
        nearest = k;
    clusters[nearest].moment += clusters[extra].moment;
    clusters[nearest].members.insert(clusters[nearest].members.end(), clusters[extra].members.begin(),
                                     clusters[extra].members.end());
  }
  std::vector<ClippedLight> lights;
  for (std::size_t k = 0; k < kept; ++k) {
    const glm::dvec3 luminance_moment =
        luminanceWeighted(clusters[k].moment[0], clusters[k].moment[1], clusters[k].moment[2]);
    const double length = glm::length(luminance_moment);
    if (!(length > 0.0)) continue;
    ClippedLight light;
    light.direction_w = luminance_moment / length;
    for (int c = 0; c < 3; ++c) light.irradiance_rgb[c] = std::max(0.0, glm::dot(clusters[k].moment[c], light.direction_w));
    double total = 0.0;
    for (const Texel* texel : clusters[k].members) total += texel->energy;
    for (const Texel* texel : clusters[k].members) {
      light.texels.push_back(texel->index);
      light.texel_share.push_back(static_cast<float>(texel->energy / total));
    }
    lights.push_back(std::move(light));
  }
  return lights;
}

}  // namespace probelight::ibl

namespace probelight::ibl {

ClippedShares clippedShares(const ClippedLight& light, const CubeMapRGB& live, double clip_level,
                            const std::vector<std::uint8_t>* resolved) {
  // Half a unit in the last place of a half float's 11-bit significand:
  // the most a clamped texel's storage moves it below the clip. A real
  // value that close below still reads 255 (a code step there is ~0.9%).
  constexpr double kStorageRounding = 1.0 / 2048.0;
  const float clipped_at = static_cast<float>(clip_level * (1.0 - kStorageRounding));
  const std::size_t per_face = static_cast<std::size_t>(live.face_size) * live.face_size;
  const bool have_resolved = resolved != nullptr && resolved->size() == per_face * kCubeFaceCount;
  ClippedShares shares;
  for (std::size_t i = 0; i < light.texels.size(); ++i) {
    const std::size_t face = light.texels[i] / per_face, index = light.texels[i] % per_face;
    if (face >= static_cast<std::size_t>(kCubeFaceCount)) return {};  // a map of another size
    const glm::vec3& texel = live.faces[face][index];
    if (std::max({texel.r, texel.g, texel.b}) >= clipped_at)
      shares.still_clipped += light.texel_share[i];
    else if (have_resolved && (*resolved)[light.texels[i]])
      shares.resolved += light.texel_share[i];
  }
  shares.still_clipped = std::min(1.0, shares.still_clipped);
  shares.resolved = std::min(1.0, shares.resolved);
  return shares;
}

double stillClippedShare(const ClippedLight& light, const CubeMapRGB& live, double clip_level) {
  return clippedShares(light, live, clip_level, nullptr).still_clipped;
}

}  // namespace probelight::ibl
