#include "ibl/virtual_lamp.hpp"

#include <algorithm>
#include <cmath>

#include "core/finite_vector.hpp"
#include "ibl/color_transfer.hpp"

namespace probelight::ibl {

std::optional<VirtualLampProblem> virtualLampProblem(const VirtualLamp& lamp) {
  if (!allFinite(lamp.position_w)) return VirtualLampProblem{"position", "must be three finite numbers"};
  if (!(lamp.position_w.z > 0.0)) return VirtualLampProblem{"position", "the lamp must be above the ground (z > 0)"};
  if (!allFinite(lamp.colour) || lamp.colour.r < 0.0 || lamp.colour.g < 0.0 || lamp.colour.b < 0.0)
    return VirtualLampProblem{"colour", "must be three finite numbers, none negative"};
  if (!std::isfinite(lamp.intensity) || lamp.intensity < 0.0)
    return VirtualLampProblem{"intensity", "must be a finite number, not negative"};
  if (!allFinite(lamp.spot_direction_w) || !(glm::length(lamp.spot_direction_w) > 0.0))
    return VirtualLampProblem{"spot_direction", "must be a direction, not zero"};
  if (!(lamp.spot_half_angle_deg > 0.0 && lamp.spot_half_angle_deg <= 180.0))
    return VirtualLampProblem{"spot_half_angle_deg", "must be in (0, 180]"};
  if (!(lamp.spot_softness_deg >= 0.0 && lamp.spot_softness_deg <= 90.0))
    return VirtualLampProblem{"spot_softness_deg", "must be in [0, 90]"};
  return std::nullopt;
}

SpotCosines spotCosines(const VirtualLamp& lamp) {
  if (lamp.spot_half_angle_deg >= 180.0) return {};
  const double half_soft = 0.5 * lamp.spot_softness_deg;
  SpotCosines result;
  result.outer = std::cos(glm::radians(std::min(lamp.spot_half_angle_deg + half_soft, 180.0)));
  result.inner = std::max(std::cos(glm::radians(std::max(lamp.spot_half_angle_deg - half_soft, 0.0))), result.outer + 1e-4);
  return result;
}

double spotWeight(const VirtualLamp& lamp, const glm::dvec3& point_w) {
  const glm::dvec3 to_point = point_w - lamp.position_w;
  const double distance = glm::length(to_point);
  if (lamp.spot_half_angle_deg >= 180.0 || !(distance > 0.0)) return 1.0;
  const SpotCosines cosines = spotCosines(lamp);
  const double c = glm::dot(to_point / distance, glm::normalize(lamp.spot_direction_w));
  const double x = std::clamp((c - cosines.outer) / (cosines.inner - cosines.outer), 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

glm::dvec3 lampRatioAtOneMetre(const VirtualLamp& lamp, const glm::dvec3& room_e_up_rgb) {
  const double y = luminance(room_e_up_rgb);
  glm::dvec3 ratio(0.0);
  for (int c = 0; c < 3; ++c)
    ratio[c] = room_e_up_rgb[c] > 0.0 ? lamp.intensity * lamp.colour[c] * y / room_e_up_rgb[c] : 0.0;
  return ratio;
}

glm::dvec3 lampToRoomRatio(const VirtualLamp& lamp, const glm::dvec3& room_e_up_rgb, const glm::dvec2& ground_w) {
  const glm::dvec3 point(ground_w, 0.0);
  const glm::dvec3 to_lamp = lamp.position_w - point;
  const double d2 = glm::dot(to_lamp, to_lamp);
  if (!(d2 > 0.0) || !(to_lamp.z > 0.0)) return glm::dvec3(0.0);
  const double cos_over_d2 = to_lamp.z / (d2 * std::sqrt(d2));
  return lampRatioAtOneMetre(lamp, room_e_up_rgb) * (cos_over_d2 * spotWeight(lamp, point));
}

double lampPoolRadiusM(const VirtualLamp& lamp, const glm::dvec3& room_e_up_rgb, double smallest_ratio) {
  const glm::dvec3 at_one_metre = lampRatioAtOneMetre(lamp, room_e_up_rgb);
  const double largest = std::max({at_one_metre.r, at_one_metre.g, at_one_metre.b});
  const double height = lamp.position_w.z;
  if (!(largest > 0.0) || !(smallest_ratio > 0.0) || !(height > 0.0)) return 0.0;
  const double d = std::cbrt(height * largest / smallest_ratio);
  return d > height ? std::sqrt(d * d - height * height) : 0.0;
}

glm::dmat4 groundShadowProjection(const glm::dvec3& lamp_w) {
  const double lx = lamp_w.x, ly = lamp_w.y, lz = lamp_w.z;
  // Rows: (lz, 0, -lx, 0), (0, lz, -ly, 0), (0, 0, 0, 0), (0, 0, -1, lz).
  glm::dmat4 m(0.0);
  m[0][0] = lz;
  m[2][0] = -lx;
  m[1][1] = lz;
  m[2][1] = -ly;
  m[2][3] = -1.0;
  m[3][3] = lz;
  return m;
}

}  // namespace probelight::ibl
