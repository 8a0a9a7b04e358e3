#include "stages/screen_motion.hpp"

#include <cmath>

namespace probelight {

void ScreenMotion::observe(double time_s, const glm::dvec2& position_px) {
  const bool finite = std::isfinite(time_s) && std::isfinite(position_px.x) && std::isfinite(position_px.y);
  if (!finite) {
    forget();
    return;
  }
  if (!samples_.empty()) {
    const double step_s = time_s - samples_.back().time_s;
    if (!(step_s > 0.0) || step_s > kLongestGapS) forget();
  }
  if (samples_.size() == 3) samples_.erase(samples_.begin());
  samples_.push_back({time_s, position_px});
}

std::optional<glm::dvec2> ScreenMotion::velocityPxPerS() const {
  if (samples_.size() < 2) return std::nullopt;
  const Sample& newest = samples_.back();
  const Sample& before = samples_[samples_.size() - 2];
  const double h2 = newest.time_s - before.time_s;
  if (samples_.size() == 2) return (newest.position_px - before.position_px) / h2;
  // The parabola through (t0, p0), (t1, p1), (t2, p2), differentiated at
  // t2; with h1 = t1 - t0, h2 = t2 - t1 (both positive, observe() keeps
  // them so).
  const Sample& oldest = samples_.front();
  const double h1 = before.time_s - oldest.time_s;
  const double h = h1 + h2;
  return oldest.position_px * (h2 / (h1 * h)) - before.position_px * (h / (h1 * h2)) +
         newest.position_px * ((h1 + 2.0 * h2) / (h2 * h));
}

std::optional<glm::dvec2> ScreenMotion::smearPx(double exposure_s) const {
  if (!(exposure_s > 0.0) || !std::isfinite(exposure_s)) return std::nullopt;
  const std::optional<glm::dvec2> velocity = velocityPxPerS();
  if (!velocity) return std::nullopt;
  return *velocity * exposure_s;
}

}  // namespace probelight
