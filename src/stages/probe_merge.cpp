#include "stages/probe_merge.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ibl/hdr_bracket.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_outline.hpp"

namespace probelight {

namespace {

ibl::ProbeAccumulatorSettings accumulatorSettings(const ibl::CameraTransfer& camera_transfer, const RigGeometry& rig,
                                                  int face_size, double clip_level) {
  ibl::ProbeAccumulatorSettings settings;
  settings.face_size = face_size;
  settings.noise.camera_transfer = camera_transfer;
  settings.noise.probe_reflectance = rig.probe_reflectance;
  settings.noise.clip_level = clip_level;
  return settings;
}

bool knownExposure(double exposure_product) { return std::isfinite(exposure_product) && exposure_product > 0.0; }

}  // namespace

ProbeMerge::ProbeMerge(const ibl::CameraTransfer& camera_transfer, const RigGeometry& rig, int face_size,
                       const ibl::ObservationSettings& observation)
    : camera_transfer_(camera_transfer),
      rig_(rig),
      observation_settings_(observation),
      clip_level_(ibl::clippedMapLevel(ibl::HdrMergeSettings{camera_transfer}, rig.probe_reflectance)),
      clip_code_(static_cast<std::uint8_t>(ibl::HdrMergeSettings{camera_transfer}.clip_code)),
      accumulator_(accumulatorSettings(camera_transfer, rig, face_size, clip_level_)),
      observation_(face_size),
      bracket_confidence_(accumulator_.texels().size(), 0.0f) {}

ProbeViewCounts ProbeMerge::addView(const ibl::MirrorBallView& view, const ibl::CubeMapRGB& map,
                                    const std::vector<float>* validity, const std::vector<std::uint8_t>* still_clipped,
                                    double to_probe_exposure, const FrameBuffer* frame) {
  ProbeViewCounts counts;
  const double scale =
      std::isfinite(to_probe_exposure) && to_probe_exposure > 0.0 ? to_probe_exposure : 1.0;
  const std::size_t per_face = static_cast<std::size_t>(accumulator_.faceSize()) * accumulator_.faceSize();
  ibl::observeBall(view, map, validity, still_clipped, clip_level_, observation_settings_, observation_);
  if (frame && !still_clipped) {
    markTexelsTouchingClippedPixels(view, *frame, scale);
    markMeasuredTexelsWithAClippedPixelInTheirFootprint(view, *frame, scale);
  }
  if (!still_clipped) boundWhereLessSureThanTheBracket(scale);
  if (frame) {
    // The frame's pixels are the light itself (no ball in between): camera
    // linear is already the map's unit.
    const ibl::LinearPixelReader read = [&](int x, int y, bool& clipped) {
      const glm::u8vec3 code = frame->rgbAt(x, y);
      clipped = std::max({code.r, code.g, code.b}) >= clip_code_;
      return glm::dvec3(ibl::decodeCameraValue(camera_transfer_, code.r / 255.0),
                        ibl::decodeCameraValue(camera_transfer_, code.g / 255.0),
                        ibl::decodeCameraValue(camera_transfer_, code.b / 255.0));
    };
    counts.texels_from_frame_around_ball = ibl::addFrameAroundBall(observation_, view, rig_, read, observation_settings_);
  }
  if (scale != 1.0)
    for (auto& face : observation_.radiance.faces)
      for (glm::vec3& texel : face) texel *= static_cast<float>(scale);
  // A bracket measures what the 8-bit views before it could only bound
  // from below: each pixel they read beside a clipped one (a sun smeared
  // into the ball's rim, the edge of a lamp) pulled their texels down.
  // Where it measured more than they kept, their estimate is taken as such
  // a bound, which its measurement then replaces (the light is the same;
  // a change that dimmed it shows in the next 8-bit view).
  if (still_clipped) {
    const std::vector<glm::vec4>& kept = accumulator_.texels();
    for (std::size_t i = 0; i < kept.size(); ++i)
      if (observation_.confidence[i] > 0.0f && !observation_.lower_bound[i] && kept[i].a != 0.0f && !(bracket_confidence_[i] > 0.0f) &&
          ibl::luminance(glm::dvec3(observation_.radiance.faces[i / per_face][i % per_face])) >
              ibl::luminance(glm::dvec3(glm::vec3(kept[i]))))
        accumulator_.demoteToLowerBound(i);
  }
  counts.merge = accumulator_.add(observation_);
  trackBracketTexels(still_clipped != nullptr);
  return counts;
}

// After each view: the texels a bracket measured (with how surely), and
// those where a later 8-bit sample replaced its measurement.
void ProbeMerge::trackBracketTexels(bool bracket) {
  const int n = accumulator_.faceSize();
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  // Surer than this, a direction is known to within the largest texel's
  // angle: a bracket that sure smeared nothing over the texel.
  const double texel_angle_rad = 0.5 * std::numbers::pi / n;
  const float sure_within_a_texel = static_cast<float>(1.0 / (texel_angle_rad * texel_angle_rad));
  for (std::size_t i = 0; i < bracket_confidence_.size(); ++i) {
    if (observation_.confidence[i] <= 0.0f) continue;
    if (bracket) {
      bracket_confidence_[i] = observation_.lower_bound[i] ? 0.0f : observation_.confidence[i];
    } else if (bracket_confidence_[i] > 0.0f && !observation_.lower_bound[i] &&
               glm::vec3(accumulator_.texels()[i]) == observation_.radiance.faces[i / per_face][i % per_face]) {
      // This view's sample replaced the bracket's: the light changed there,
      // or (a bracket unsure of the direction, a view at least as sure)
      // what the bracket smeared over the texel is elsewhere.
      const bool resolves_a_smear = bracket_confidence_[i] < sure_within_a_texel &&
                                    observation_.confidence[i] >= bracket_confidence_[i];
      bracket_confidence_[i] = resolves_a_smear ? kResolvedBySharperView : 0.0f;
    }
  }
}

// An 8-bit view that sees a texel near its ball's rim (its direction
// uncertain by more texels than the accumulator lets seed a change: a pixel
// there spans many texels), less surely than the bracket that measured it,
// and reads less there: its sample mixed in the darker texels around, or a
// clipped pixel the marking above did not reach (between its nine
// directions). It says "at least" only. A sharper view that reads less is a
// measurement: the light dimmed (the accumulator then replaces the
// bracket's value), or the bracket's texel average differs from a point
// sample.
void ProbeMerge::boundWhereLessSureThanTheBracket(double to_probe_exposure) {
  const int n = accumulator_.faceSize();
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  // ProbeAccumulator's search radius: 1 / sqrt(c) over the largest texel angle.
  const double rim_sigma_rad = accumulator_.settings().max_search_texels * 0.5 * std::numbers::pi / n;
  const float rim_confidence = static_cast<float>(1.0 / (rim_sigma_rad * rim_sigma_rad));
  for (std::size_t i = 0; i < bracket_confidence_.size(); ++i) {
    const float c = observation_.confidence[i];
    if (c <= 0.0f || observation_.lower_bound[i] || !(c < rim_confidence) || !(c < bracket_confidence_[i])) continue;
    if (to_probe_exposure * ibl::luminance(glm::dvec3(observation_.radiance.faces[i / per_face][i % per_face])) <
        ibl::luminance(glm::dvec3(accumulator_.radiance(i))))
      observation_.lower_bound[i] = 1;
  }
}

bool ProbeMerge::measuredAboveClip(std::size_t texel) const {
  const glm::vec4& kept = accumulator_.texels()[texel];
  return kept.a > 0.0f && std::max({kept.r, kept.g, kept.b}) > static_cast<float>(clip_level_);
}

// An 8-bit map's texel is a bilinear sample of the ball's pixels: where one
// of them clipped, the texel's value is below the light's whatever it
// reads (a sun a pixel wide beside sky averages to sky-like codes). Such a
// texel is a lower bound: it must not overwrite, nor average down, what a
// bracket measured there. A texel's sample reads the pixels within one
// pixel of its point on the ball, so the texels whose points lie in the
// 3 x 3 pixels around a clipped pixel are marked (their directions at the
// square's corners, edges and centre), and their neighbours, for the
// texels between those nine directions where the ball's rim spreads a
// pixel over several texels. Only where the probe holds a bracket's
// measurement above the sample: elsewhere a lower bound would be raised to
// the largest of the views' samples, and the maps of a probe no bracket
// has seen would hold more than an 8-bit camera can know beside a clipped
// light (each view mixes it into other texels).
void ProbeMerge::markTexelsTouchingClippedPixels(const ibl::MirrorBallView& view, const FrameBuffer& frame,
                                                 double to_probe_exposure) {
  const int n = accumulator_.faceSize();
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  std::vector<std::uint8_t>& touched = touched_by_clipped_;
  touched.assign(observation_.texelCount(), 0);
  const ibl::ProbeOutline outline = ibl::computeProbeOutline(view);
  if (!outline.valid) return;
  const int x0 = std::max(0, static_cast<int>(std::floor(outline.min_px.x)));
  const int x1 = std::min(frame.width_px - 1, static_cast<int>(std::ceil(outline.max_px.x)));
  const int y0 = std::max(0, static_cast<int>(std::floor(outline.min_px.y)));
  const int y1 = std::min(frame.height_px - 1, static_cast<int>(std::ceil(outline.max_px.y)));
  if (x1 < x0 || y1 < y0) return;
  // The pixels within one of a clipped pixel (the outline's box grown by
  // one), each solved for its direction once: a sun's pixels share most of
  // their neighbours.
  const int width = x1 - x0 + 3, height = y1 - y0 + 3;
  std::vector<std::uint8_t>& near_clipped = near_clipped_pixels_;
  near_clipped.assign(static_cast<std::size_t>(width) * height, 0);
  bool any_clipped = false;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const glm::u8vec3 code = frame.rgbAt(x, y);
      if (std::max({code.r, code.g, code.b}) < clip_code_) continue;
      any_clipped = true;
      for (int dy = 0; dy <= 2; ++dy)
        for (int dx = 0; dx <= 2; ++dx)
          near_clipped[static_cast<std::size_t>(y - y0 + dy) * width + (x - x0 + dx)] = 1;
    }
  if (!any_clipped) return;
  bool any = false;
  for (int row = 0; row < height; ++row)
    for (int column = 0; column < width; ++column) {
      if (!near_clipped[static_cast<std::size_t>(row) * width + column]) continue;
      const glm::dvec2 pixel(x0 - 1 + column, y0 - 1 + row);
      const std::optional<glm::dvec3> direction = ibl::pixelToReflectedDirection(view, pixel);
      if (!direction) continue;
      const ibl::CubeTexelCoord coord = ibl::directionToCubeCoord(*direction);
      const int tx = std::clamp(static_cast<int>(coord.s * n), 0, n - 1);
      const int ty = std::clamp(static_cast<int>(coord.t * n), 0, n - 1);
      touched[static_cast<std::size_t>(coord.face) * per_face + static_cast<std::size_t>(ty) * n + tx] = 1;
      any = true;
    }
  if (!any) return;
  for (int face = 0; face < ibl::kCubeFaceCount; ++face)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        if (!touched[face * per_face + static_cast<std::size_t>(y) * n + x]) continue;
        for (int ny = std::max(0, y - 1); ny <= std::min(n - 1, y + 1); ++ny)
          for (int nx = std::max(0, x - 1); nx <= std::min(n - 1, x + 1); ++nx) {
            const std::size_t i = face * per_face + static_cast<std::size_t>(ny) * n + nx;
            if (observation_.confidence[i] > 0.0f && bracket_confidence_[i] > 0.0f &&
                to_probe_exposure * ibl::luminance(glm::dvec3(observation_.radiance.faces[face][i % per_face])) <
                    ibl::luminance(glm::dvec3(accumulator_.radiance(i))))
              observation_.lower_bound[i] = 1;
          }
      }
}

// The marking above samples nine directions per clipped pixel; a light
// smaller than a texel (a sun: 0.5 degrees against 1.4) lies between them
// as often as not, and the GPU's map samples each texel at its centre: an
// 8-bit view then reads sky where a bracket measured the sun, and would
// replace it though the sun is still there, clipped in this very frame.
// So each texel where the probe holds a bracket's measurement above the
// clip, and this view reads less, is checked whole: the pixels its corners
// and centre show, and one more around them (the bilinear sample's reach).
// A clipped pixel among them makes the view's sample a lower bound. A light
// that went (no clipped pixel there) is measured, and replaces it.
void ProbeMerge::markMeasuredTexelsWithAClippedPixelInTheirFootprint(const ibl::MirrorBallView& view,
                                                                    const FrameBuffer& frame,
                                                                    double to_probe_exposure) {
  const int n = accumulator_.faceSize();
  const std::size_t per_face = static_cast<std::size_t>(n) * n;
  for (std::size_t i = 0; i < bracket_confidence_.size(); ++i) {
    if (!(bracket_confidence_[i] > 0.0f) || !(observation_.confidence[i] > 0.0f) || observation_.lower_bound[i] ||
        !measuredAboveClip(i))
      continue;
    const int face = static_cast<int>(i / per_face);
    const int x = static_cast<int>(i % per_face) % n, y = static_cast<int>(i % per_face) / n;
    if (!(to_probe_exposure * ibl::luminance(glm::dvec3(observation_.radiance.faces[face][i % per_face])) <
          ibl::luminance(glm::dvec3(accumulator_.radiance(i)))))
      continue;
    glm::dvec2 low(INFINITY), high(-INFINITY);
    for (const glm::dvec2 at : {glm::dvec2(0.5, 0.5), glm::dvec2(0.0, 0.0), glm::dvec2(1.0, 0.0), glm::dvec2(0.0, 1.0),
                                glm::dvec2(1.0, 1.0)}) {
      const ibl::CubeTexelCoord coord{face, (x + at.x) / n, (y + at.y) / n};
      // Three Newton steps place the pixel to far under the pixel of margin
      // added below (the solve converges quadratically from the bisector).
      if (const std::optional<glm::dvec2> pixel =
              ibl::reflectedDirectionToPixel(view, ibl::cubeCoordToDirection(coord), 3)) {
        low = glm::min(low, *pixel);
        high = glm::max(high, *pixel);
      }
    }
    if (!(low.x <= high.x)) continue;  // no part of it in the ball's sight
    const int x0 = std::max(0, static_cast<int>(std::floor(low.x)) - 1);
    const int y0 = std::max(0, static_cast<int>(std::floor(low.y)) - 1);
    const int x1 = std::min(frame.width_px - 1, static_cast<int>(std::ceil(high.x)) + 1);
    const int y1 = std::min(frame.height_px - 1, static_cast<int>(std::ceil(high.y)) + 1);
    bool clipped = false;
    for (int py = y0; py <= y1 && !clipped; ++py)
      for (int px = x0; px <= x1 && !clipped; ++px) {
        const glm::u8vec3 code = frame.rgbAt(px, py);
        clipped = std::max({code.r, code.g, code.b}) >= clip_code_;
      }
    if (clipped) observation_.lower_bound[i] = 1;
  }
}

std::vector<std::uint8_t> ProbeMerge::texelsResolvedBySharperViews() const {
  std::vector<std::uint8_t> resolved(bracket_confidence_.size());
  for (std::size_t i = 0; i < resolved.size(); ++i)
    resolved[i] = bracket_confidence_[i] == kResolvedBySharperView ? 1 : 0;
  return resolved;
}

void ProbeMerge::followExposure(double exposure_product) {
  if (!knownExposure(exposure_product)) return;
  if (knownExposure(exposure_product_) && exposure_product != exposure_product_)
    accumulator_.scaleRadiance(exposure_product / exposure_product_);
  exposure_product_ = exposure_product;
}

void ProbeMerge::followWhiteBalance(double red_gain, double blue_gain) {
  auto known = [](double gain) { return std::isfinite(gain) && gain > 0.0; };
  glm::dvec3 factor(1.0);
  if (known(red_gain) && known(red_gain_)) factor.r = red_gain / red_gain_;
  if (known(blue_gain) && known(blue_gain_)) factor.b = blue_gain / blue_gain_;
  if (factor != glm::dvec3(1.0)) accumulator_.scaleRadiance(factor);
  if (known(red_gain)) red_gain_ = red_gain;
  if (known(blue_gain)) blue_gain_ = blue_gain;
}

double ProbeMerge::toProbeExposure(double exposure_product) const {
  if (!knownExposure(exposure_product) || !knownExposure(exposure_product_)) return 1.0;
  return exposure_product_ / exposure_product;
}

bool ProbeMerge::holdsAboveClip() const {
  for (std::size_t i = 0; i < accumulator_.texels().size(); ++i)
    if (measuredAboveClip(i)) return true;
  return false;
}

std::array<double, 6> ProbeMerge::axisIrradiance() const {
  const int n = accumulator_.faceSize();
  const std::vector<glm::vec3>& directions = ibl::texelDirections(n);
  const std::vector<glm::vec4>& texels = accumulator_.texels();
  const float clip = static_cast<float>(clip_level_);
  std::array<double, 6> irradiance{};  // +x +y +z, then -x -y -z
  for (std::size_t i = 0; i < texels.size(); ++i) {
    if (texels[i].a == 0.0f) continue;
    const glm::vec3 rgb = glm::min(glm::vec3(texels[i]), glm::vec3(clip));
    const double energy = ibl::luminance(glm::dvec3(rgb)) * accumulator_.solidAngleSr(i);
    for (int axis = 0; axis < 3; ++axis) {
      const double c = directions[i][axis];
      irradiance[c > 0.0 ? axis : axis + 3] += energy * std::abs(c);
    }
  }
  return irradiance;
}

bool ProbeMerge::restore(const std::vector<glm::vec4>& texels, double exposure_product, std::string& error) {
  if (!accumulator_.restore(texels, error)) return false;
  exposure_product_ = knownExposure(exposure_product) ? exposure_product : 0.0;
  // Only a bracket measures above the clip (how sure it was is not kept:
  // as sure as any view).
  for (std::size_t i = 0; i < bracket_confidence_.size(); ++i)
    bracket_confidence_[i] = measuredAboveClip(i) ? INFINITY : 0.0f;
  return true;
}

}  // namespace probelight
