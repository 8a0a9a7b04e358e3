#include "stages/light_transition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "ibl/color_transfer.hpp"

namespace probelight {

ibl::DomeLight blendLights(const ibl::DomeLight& from, const ibl::DomeLight& to, double t) {
  t = std::clamp(t, 0.0, 1.0);
  ibl::DomeLight light;
  // Great-circle interpolation (slerp) of the two unit directions.
  const double cosine = std::clamp(glm::dot(from.direction_w, to.direction_w), -1.0, 1.0);
  const double angle = std::acos(cosine);
  if (angle < 1e-6) {
    light.direction_w = to.direction_w;
  } else if (angle > std::numbers::pi - 1e-5) {  // opposite: any great circle; go over the zenith
    light.direction_w = glm::normalize((1.0 - t) * from.direction_w + t * to.direction_w + glm::dvec3(0, 0, 1e-3));
  } else {
    light.direction_w = (std::sin((1.0 - t) * angle) * from.direction_w + std::sin(t * angle) * to.direction_w) /
                        std::sin(angle);
  }
  light.rgb = (1.0 - t) * from.rgb + t * to.rgb;
  light.spread_rad = (1.0 - t) * from.spread_rad + t * to.spread_rad;
  light.solid_angle_sr = (1.0 - t) * from.solid_angle_sr + t * to.solid_angle_sr;
  return light;
}

void LightTransition::retarget(const std::vector<ibl::DomeLight>& target, double now_s) {
  const std::vector<ibl::DomeLight> shown = at(now_s);
  const bool first = pairs_.empty();
  target_ = target;
  pairs_.clear();
  start_s_ = now_s;
  if (first) {
    for (const ibl::DomeLight& light : target) pairs_.push_back({light, light});
    return;
  }
  // Greedy pairing by nearest direction, most energetic new lights first, so
  // that the brightest lights move the least.
  std::vector<std::size_t> order(target.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  using ibl::luminance;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return luminance(target[a].rgb) > luminance(target[b].rgb); });
  std::vector<bool> used(shown.size(), false);
  for (std::size_t i : order) {
    double best = -2.0;
    std::size_t partner = shown.size();
    for (std::size_t j = 0; j < shown.size(); ++j)
      if (!used[j] && glm::dot(shown[j].direction_w, target[i].direction_w) > best) {
        best = glm::dot(shown[j].direction_w, target[i].direction_w);
        partner = j;
      }
    if (partner < shown.size()) {
      used[partner] = true;
      pairs_.push_back({shown[partner], target[i]});
    } else {
      ibl::DomeLight dark = target[i];
      dark.rgb = glm::dvec3(0.0);
      pairs_.push_back({dark, target[i]});
    }
  }
  for (std::size_t j = 0; j < shown.size(); ++j)
    if (!used[j]) {
      ibl::DomeLight dark = shown[j];
      dark.rgb = glm::dvec3(0.0);
      pairs_.push_back({shown[j], dark});
    }
}

std::vector<ibl::DomeLight> LightTransition::at(double now_s) const {
  const double t = fade_s_ > 0.0 ? (now_s - start_s_) / fade_s_ : 1.0;
  std::vector<ibl::DomeLight> lights;
  for (const Pair& pair : pairs_) {
    ibl::DomeLight light = blendLights(pair.from, pair.to, t);
    // Lights that have faded out are gone.
    if (t >= 1.0 && pair.to.rgb == glm::dvec3(0.0) && pair.from.rgb != glm::dvec3(0.0)) continue;
    lights.push_back(light);
  }
  return lights;
}

bool LightTransition::moving(double now_s) const {
  return !pairs_.empty() && fade_s_ > 0.0 && now_s - start_s_ < fade_s_;
}

}  // namespace probelight
