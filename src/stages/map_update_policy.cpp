#include "stages/map_update_policy.hpp"

#include <algorithm>
#include <cmath>

namespace probelight {

const char* toString(MapSkipReason reason) {
  switch (reason) {
    case MapSkipReason::kNone: return "";
    case MapSkipReason::kNoTag: return "no tag";
    case MapSkipReason::kBallNotInView: return "ball not fully in view";
    case MapSkipReason::kBallTooSmall: return "ball too small";
    case MapSkipReason::kBallSaturated: return "ball saturated";
    case MapSkipReason::kBallDark: return "ball dark";
    case MapSkipReason::kCameraMoving: return "camera moving";
    case MapSkipReason::kImageUnchanged: return "ball image unchanged";
  }
  return "";
}

const char* toString(MapUpdateCause cause) {
  switch (cause) {
    case MapUpdateCause::kNone: return "";
    case MapUpdateCause::kFirst: return "first";
    case MapUpdateCause::kFreshRequested: return "fresh requested";
    case MapUpdateCause::kImageChanged: return "image changed";
    case MapUpdateCause::kMaxAge: return "max age";
  }
  return "";
}

BallSignature sampleBallSignature(const LumaView& luma, glm::dvec2 center_px, double radius_px) {
  constexpr int n = BallSignature::kCells;
  BallSignature signature;
  signature.center_px = center_px;
  signature.radius_px = radius_px;
  signature.mean.assign(n * n, 0.0f);
  signature.count.assign(n * n, 0);
  // Non-finite numbers would make the pixel bounds below undefined (a NaN
  // cast to int); such a signature simply holds no pixel.
  if (!luma.data || luma.width <= 0 || luma.height <= 0 || !(radius_px > 0.0) || !std::isfinite(radius_px) ||
      !std::isfinite(center_px.x) || !std::isfinite(center_px.y))
    return signature;

  const double extent = BallSignature::kExtent * radius_px;
  const double cell = 2.0 * extent / n;
  const int x0 = std::max(0, static_cast<int>(std::ceil(center_px.x - extent)));
  const int x1 = std::min(luma.width - 1, static_cast<int>(std::floor(center_px.x + extent)));
  const int y0 = std::max(0, static_cast<int>(std::ceil(center_px.y - extent)));
  const int y1 = std::min(luma.height - 1, static_cast<int>(std::floor(center_px.y + extent)));
  std::vector<double> sum(n * n, 0.0);
  for (int y = y0; y <= y1; ++y) {
    const double dy = y - center_px.y;
    const std::uint8_t* row = luma.data + static_cast<std::ptrdiff_t>(y) * luma.stride;
    const int cy = std::clamp(static_cast<int>((dy + extent) / cell), 0, n - 1);
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - center_px.x;
      if (dx * dx + dy * dy > extent * extent) continue;
      const int cx = std::clamp(static_cast<int>((dx + extent) / cell), 0, n - 1);
      sum[cy * n + cx] += row[x];
      ++signature.count[cy * n + cx];
    }
  }
  for (int i = 0; i < n * n; ++i)
    if (signature.count[i] > 0) signature.mean[i] = static_cast<float>(sum[i] / signature.count[i]);
  return signature;
}

BallExposure measureBallExposure(const BallSignature& signature) {
  BallExposure exposure;
  int saturated = 0;
  int dark = 0;
  for (size_t i = 0; i < signature.mean.size() && i < signature.count.size(); ++i) {
    if (signature.count[i] == 0) continue;
    ++exposure.cells;
    if (signature.mean[i] >= kSaturatedCode) ++saturated;
    if (signature.mean[i] <= kDarkCode) ++dark;
  }
  if (exposure.cells > 0) {
    exposure.saturated_fraction = static_cast<double>(saturated) / exposure.cells;
    exposure.dark_fraction = static_cast<double>(dark) / exposure.cells;
  }
  return exposure;
}

std::optional<double> signatureDifference(const BallSignature& a, const BallSignature& b) {
  if (a.mean.size() != b.mean.size() || a.count.size() != a.mean.size() || b.count.size() != b.mean.size())
    return std::nullopt;
  double sum = 0.0;
  int cells = 0;
  for (size_t i = 0; i < a.mean.size(); ++i) {
    if (a.count[i] == 0 || b.count[i] == 0) continue;
    sum += std::abs(static_cast<double>(a.mean[i]) - b.mean[i]);
    ++cells;
  }
  if (cells == 0) return std::nullopt;
  return sum / cells;
}

MapUpdatePolicy::MapUpdatePolicy(MapUpdateSettings settings) : settings_(settings) {}

MapUpdateDecision MapUpdatePolicy::decide(const MapFrameInput& frame) {
  MapUpdateDecision decision;
  ++frames_since_update_;
  auto skip = [&](MapSkipReason reason) {
    decision.skip = reason;
    return decision;
  };

  if (!frame.tag_found) {
    // Steadiness is between consecutive frames: after a gap it is unknown.
    previous_.reset();
    return skip(MapSkipReason::kNoTag);
  }
  const ibl::ProbeOutline& outline = frame.outline;
  // A non-finite outline or pose (NaN from a degenerate pose) is no outline:
  // every comparison below would be false and the sampling undefined.
  const glm::dmat3& R = frame.rotation_cam_from_world;
  const bool finite = std::isfinite(outline.center_px.x) && std::isfinite(outline.center_px.y) &&
                      std::isfinite(outline.radius_px) && std::isfinite(R[0][0] + R[0][1] + R[0][2] + R[1][0] +
                                                                        R[1][1] + R[1][2] + R[2][0] + R[2][1] + R[2][2]);
  if (!outline.valid || !finite) {
    previous_.reset();
    return skip(MapSkipReason::kBallNotInView);
  }

  // Steadiness against the previous frame, measured even when this frame is
  // skipped for another reason, so that the next one can be judged.
  bool steady = false;
  if (previous_) {
    decision.center_shift_px = glm::length(outline.center_px - previous_->center_px);
    decision.radius_change_px = std::abs(outline.radius_px - previous_->radius_px);
    decision.rotation_change_deg = rotationAngleDeg(frame.rotation_cam_from_world, previous_->rotation);
    steady = *decision.center_shift_px <= settings_.max_center_shift_px &&
             *decision.radius_change_px <= settings_.max_radius_change_px &&
             *decision.rotation_change_deg <= settings_.max_rotation_change_deg;
  }
  previous_ = PreviousFrame{outline.center_px, outline.radius_px, frame.rotation_cam_from_world};

  if (!outline.fully_in_image) return skip(MapSkipReason::kBallNotInView);
  if (outline.radius_px < settings_.min_probe_radius_px) return skip(MapSkipReason::kBallTooSmall);

  // This frame's own signature: the exposure test here, the new reference
  // below when the maps are updated. Checked before "no maps yet": a white
  // or black map is worse than none (the object would be drawn lit wrongly),
  // and after it, it would replace the last good one.
  BallSignature now = sampleBallSignature(frame.luma, outline.center_px, outline.radius_px);
  const BallExposure exposure = measureBallExposure(now);
  decision.saturated_fraction = exposure.saturated_fraction;
  decision.dark_fraction = exposure.dark_fraction;
  if (exposure.cells > 0 && exposure.saturated_fraction >= kUnusableCellFraction)
    return skip(MapSkipReason::kBallSaturated);
  if (exposure.cells > 0 && exposure.dark_fraction >= kUnusableCellFraction) return skip(MapSkipReason::kBallDark);

  const float smoothed_weight = static_cast<float>(std::clamp(settings_.smoothing_new_weight, 0.0, 1.0));
  if (!have_maps_) {
    // No maps yet: the object is not drawn at all, so even a frame whose
    // steadiness cannot be judged (the first) or that moves is better.
    decision.cause = MapUpdateCause::kFirst;
    decision.new_weight = 1.0f;
  } else if (!steady) {
    return skip(MapSkipReason::kCameraMoving);
  } else if (fresh_requested_) {
    decision.cause = MapUpdateCause::kFreshRequested;
    decision.new_weight = 1.0f;
  } else {
    const BallSignature now_on_reference_grid =
        sampleBallSignature(frame.luma, reference_.center_px, reference_.radius_px);
    decision.image_change_code = signatureDifference(now_on_reference_grid, reference_);
    // No common cell (cannot happen while steady and fully in view, but a
    // measure that cannot be made is no reason to keep a map): update.
    if (!decision.image_change_code || *decision.image_change_code > settings_.change_threshold_code)
      decision.cause = MapUpdateCause::kImageChanged;
    else if (frames_since_update_ >= settings_.max_age_frames)
      decision.cause = MapUpdateCause::kMaxAge;
    else
      return skip(MapSkipReason::kImageUnchanged);
    decision.new_weight = smoothed_weight;
  }

  // Update: the reference becomes what the maps now hold, on this frame's grid.
  decision.update = true;
  if (decision.new_weight < 1.0f && !reference_.empty()) {
    const float w = decision.new_weight;
    for (size_t i = 0; i < now.mean.size(); ++i)
      if (now.count[i] > 0 && reference_.count[i] > 0) now.mean[i] = w * now.mean[i] + (1.0f - w) * reference_.mean[i];
  }
  reference_ = std::move(now);
  have_maps_ = true;
  fresh_requested_ = false;
  frames_since_update_ = 0;
  return decision;
}

}  // namespace probelight
