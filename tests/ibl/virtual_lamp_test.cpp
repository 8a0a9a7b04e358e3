// The virtual lamp's maths (ibl/virtual_lamp.hpp): inverse square and
// cosine against the room's light, the spot's edge, the pool's reach, and
// the planar projection that casts the object's shadow from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "ibl/color_transfer.hpp"
#include "ibl/virtual_lamp.hpp"

namespace probelight::ibl {
namespace {

TEST(VirtualLamp, RatioFallsAsCosineOverDistanceSquaredInTheCamerasColours) {
  VirtualLamp lamp;
  lamp.position_w = {0.1, -0.2, 0.5};
  lamp.colour = {1.0, 0.5, 0.25};
  lamp.intensity = 0.2;
  const glm::dvec3 room(2.0, 1.0, 0.5);  // a yellowish room's light
  // Straight below, 0.5 m: intensity / 0.25 in luminance units, in the
  // camera's colours (white would be the room's luminance in each channel).
  const glm::dvec3 below = lampToRoomRatio(lamp, room, {0.1, -0.2});
  const double y = luminance(room);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(below[c], 0.2 * lamp.colour[c] * y / room[c] / 0.25, 1e-12);
  // 0.5 m aside: d^2 = 0.5, cos = 0.5 / sqrt(0.5).
  const glm::dvec3 aside = lampToRoomRatio(lamp, room, {0.6, -0.2});
  EXPECT_NEAR(aside.g / below.g, (0.5 / std::sqrt(0.5)) / 0.5 * 0.25, 1e-12);
  // The pool's reach: where the largest channel's ratio is the one asked.
  const double smallest = 1.0 / 510.0;
  const double reach = lampPoolRadiusM(lamp, room, smallest);
  const glm::dvec3 at_edge = lampToRoomRatio(lamp, room, {0.1 + reach, -0.2});
  EXPECT_NEAR(std::max({at_edge.r, at_edge.g, at_edge.b}), smallest, 1e-9);
  EXPECT_EQ(lampPoolRadiusM(lamp, room, 1e9), 0.0);
  // A lamp with no light, or a room with none.
  lamp.intensity = 0.0;
  EXPECT_EQ(lampToRoomRatio(lamp, room, {0.0, 0.0}), glm::dvec3(0.0));
  EXPECT_EQ(lampToRoomRatio(VirtualLamp{}, glm::dvec3(0.0), {0.0, 0.0}), glm::dvec3(0.0));
}

TEST(VirtualLamp, ASpotLightsItsConeAndFadesAcrossItsEdge) {
  VirtualLamp spot;
  spot.position_w = {0.0, 0.0, 1.0};
  spot.spot_direction_w = {0.0, 0.0, -2.0};  // any length
  spot.spot_half_angle_deg = 30.0;
  spot.spot_softness_deg = 10.0;
  auto at = [&](double off_axis_deg) {
    return spotWeight(spot, glm::dvec3(std::tan(glm::radians(off_axis_deg)), 0.0, 0.0));
  };
  EXPECT_DOUBLE_EQ(at(0.0), 1.0);
  EXPECT_DOUBLE_EQ(at(24.9), 1.0);
  EXPECT_DOUBLE_EQ(at(35.1), 0.0);
  EXPECT_GT(at(29.0), at(31.0));
  // The edge is a smoothstep in the cosine (as the shader's): at its
  // middle angle, x = (cos 30 - cos 35) / (cos 25 - cos 35) = 0.537, 0.556.
  const double x = (std::cos(glm::radians(30.0)) - std::cos(glm::radians(35.0))) /
                   (std::cos(glm::radians(25.0)) - std::cos(glm::radians(35.0)));
  EXPECT_NEAR(at(30.0), x * x * (3.0 - 2.0 * x), 1e-9);
  VirtualLamp point;
  EXPECT_DOUBLE_EQ(spotWeight(point, glm::dvec3(5.0, 0.0, 0.0)), 1.0);
  const SpotCosines hard = [] {
    VirtualLamp l;
    l.spot_half_angle_deg = 20.0;
    l.spot_softness_deg = 0.0;
    return spotCosines(l);
  }();
  EXPECT_GT(hard.inner, hard.outer);
}

TEST(VirtualLamp, TheProjectionPutsAPointsShadowWhereTheLampsRayThroughItMeetsTheGround) {
  const glm::dvec3 lamp(0.1, -0.05, 0.3);
  const glm::dmat4 flatten = groundShadowProjection(lamp);
  for (const glm::dvec3 p : {glm::dvec3(0.0, 0.0, 0.07), glm::dvec3(0.05, 0.02, 0.2), glm::dvec3(-0.3, 0.1, 0.0)}) {
    const glm::dvec4 h = flatten * glm::dvec4(p, 1.0);
    const glm::dvec3 shadow(h.x / h.w, h.y / h.w, h.z / h.w);
    // On the ground, and on the line from the lamp through p.
    EXPECT_NEAR(shadow.z, 0.0, 1e-12);
    const glm::dvec3 along = glm::cross(shadow - lamp, p - lamp);
    EXPECT_NEAR(glm::length(along), 0.0, 1e-12);
  }
}

TEST(VirtualLamp, SaysWhichFieldIsWrong) {
  VirtualLamp lamp;
  EXPECT_FALSE(virtualLampProblem(lamp));
  lamp.position_w.z = -0.1;
  EXPECT_EQ(virtualLampProblem(lamp)->field, "position");
  lamp = VirtualLamp{};
  lamp.intensity = std::nan("");
  EXPECT_EQ(virtualLampProblem(lamp)->field, "intensity");
  lamp = VirtualLamp{};
  lamp.spot_direction_w = glm::dvec3(0.0);
  EXPECT_EQ(virtualLampProblem(lamp)->field, "spot_direction");
}

}  // namespace
}  // namespace probelight::ibl
