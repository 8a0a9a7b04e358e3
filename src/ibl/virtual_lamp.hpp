// A virtual lamp lighting the real ground (issue 19, seed D): the maths,
// apart from the renderer (passes/virtual_lamp_light draws it).
//
// The lamp is a point light, or a spot when its cone is under a
// hemisphere. Its light is given against the room's own light on the
// ground, so that a user can say how bright it is without a light meter:
// `intensity` is the lamp's irradiance on the ground 1 m straight below it
// (inverse-square, cosine), over the luminance of the ground's irradiance
// from the room, and `colour` its colour in the camera's terms (white: the
// camera's white). The room's light is the diffuse map's upward irradiance
// E_room (per channel) as the lights were last fitted, so the lamp keeps
// its brightness while the camera's exposure moves.
//
// On the ground, albedo / pi = frame pixel / E_room (the frame's light
// divided by the light the maps say reaches it), and the lamp adds
// albedo / pi x E_lamp: per channel, the pixel times
//   ratio(p) = E_lamp(p) / E_room = intensity colour Y(E_room) / E_room
//              x cos(theta) / d^2 x spot(p) x visible(p),
// visible(p) 0 where the object stands between p and the lamp. With the
// dome's shadow fraction s(p) (passes/ground_shadow) the ground is the
// pixel times s + ratio.
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

namespace probelight::ibl {

struct VirtualLamp {
  glm::dvec3 position_w{0.08, -0.06, 0.25};  // metres, in the tag's frame (z up)
  glm::dvec3 colour{1.0, 0.85, 0.65};        // linear, in the camera's terms (1, 1, 1: its white)
  double intensity = 0.03;                   // E at 1 m below / the room's ground luminance
  // A spot's axis and its cone's half-angle; 180: a point light, all round.
  glm::dvec3 spot_direction_w{0.0, 0.0, -1.0};
  double spot_half_angle_deg = 180.0;
  double spot_softness_deg = 5.0;  // the cone's edge fades over this much
};

// Why the lamp cannot be used, naming the field (probelight.yaml's name):
// a non-finite or negative value, a lamp at or under the ground, a zero
// direction, a spot's angle out of range.
struct VirtualLampProblem {
  std::string field;
  std::string message;
};
std::optional<VirtualLampProblem> virtualLampProblem(const VirtualLamp& lamp);

// The cosines of the angle off the spot's axis where its light ends
// (outer: half-angle + softness / 2) and is whole (inner: half-angle -
// softness / 2, a little above outer when the softness is 0); for a point
// light -2 and -1.5, which every direction passes.
struct SpotCosines {
  double outer = -2.0, inner = -1.5;
};
SpotCosines spotCosines(const VirtualLamp& lamp);
// The spot's weight toward point p: smoothstep(outer, inner, cos of the
// angle off its axis), as the shader weighs it; 1 for a point light.
double spotWeight(const VirtualLamp& lamp, const glm::dvec3& point_w);

// E_lamp(p) / E_room per channel at ground point (x, y, 0), unshadowed.
// room_e_up_rgb: the room's upward irradiance on the ground (any units:
// only its colour is used).
glm::dvec3 lampToRoomRatio(const VirtualLamp& lamp, const glm::dvec3& room_e_up_rgb, const glm::dvec2& ground_w);

// The lamp's ratio at 1 m below it, per channel: intensity colour Y(E_room) / E_room.
glm::dvec3 lampRatioAtOneMetre(const VirtualLamp& lamp, const glm::dvec3& room_e_up_rgb);

// How far from the point under the lamp its ratio stays at or above
// `smallest_ratio` (its largest channel): where d^3 = h x largest / smallest
// (cos theta / d^2 = h / d^3); 0 when it never reaches it.
double lampPoolRadiusM(const VirtualLamp& lamp, const glm::dvec3& room_e_up_rgb, double smallest_ratio);

// The planar projection from the lamp onto the ground z = 0: a point P
// maps to (lz px - lx pz, lz py - ly pz, 0, lz - pz), homogeneous; its
// shadow. Columns, as glm. Meaningful for points below the lamp.
glm::dmat4 groundShadowProjection(const glm::dvec3& lamp_w);

}  // namespace probelight::ibl
