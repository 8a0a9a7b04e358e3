// The floor a surface reflects next to itself. The maps are the world seen
// from the ball's centre, as if everything were far away: right for the
// sky and the room, wrong for the floor under a model. A metal's sides and
// underside reflect the floor beside the model, a few centimetres away,
// where the model's own shadow lies; the maps show the floor around the
// ball instead, unshadowed, and from the ball's place rather than the
// model's.
//
// So a reflected direction that goes down is followed to where it meets the
// ground plane z = 0 (the tag's floor), the maps are read in the direction
// in which they show that ground point (a parallax-corrected lookup onto a
// plane proxy: Lagarde and Zanuttini, "Local image-based lighting with
// parallax-corrected cubemaps", 2012), and the light is scaled by the
// ground-shadow fraction there (passes/ground_shadow's texture: the share
// of the floor's light the model leaves it). The floor is Lambertian as far
// as the maps know it, so the ball's view of the point stands for the
// surface's.
//
// The maps' direction d shows the floor from the ball's surface, not its
// centre: from the point whose normal halves d and the way to the camera,
// c + R normalize(d + v). Near things shift by the ball's radius (3 cm
// against a floor 10-20 cm away: 10 degrees and more), so d is found by
// fixed-point steps d <- normalize(g - c - R normalize(d + v)) from the
// centre's direction; each step shrinks the error by about R / |g - c|.
//
// The mirror rung reads the floor from the camera's own frame where the
// ground point is in it: the camera sees the floor beside the model
// directly, pixel for pixel (the tag's cells sharp), where the ball shows
// it squeezed toward its rim, a few pixels for the whole tag. Toward the
// frame's edge the frame hands over to the maps over kCameraFloorMarginPx,
// so the reflection has no seam there. The glossy rungs keep the maps: they
// are the floor already blurred by their lobes, which one camera pixel is
// not.
//
// Where the reflected ray goes up, nothing changes. As it approaches the
// horizon from below, the ground point runs off to infinity and the
// corrected direction tends to the ray's own, so there is no seam.
#pragma once

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::ibl {

// Ground points further than this along the ray are as good as the
// horizon (the corrected direction is within 0.3 deg of the ray's for a
// ball 10 cm up): the search stops there, which also keeps the distance in
// a 16-bit float's range on the GPU.
constexpr float kNearFloorMaxDistance_m = 20.0f;

struct NearFloorLookup {
  bool meets_ground = false;        // the direction goes down
  glm::vec3 ground_point_w{0.0f};   // where it meets z = 0 (meets_ground)
  glm::vec3 map_direction_w{0.0f};  // unit: where to read the maps
};

// The ball the maps were made from: its centre and radius (W metres) and
// the unit direction from its centre to the camera that saw it.
struct NearFloorBall {
  glm::vec3 centre_w{0.0f};
  float radius_m = 0.0f;
  glm::vec3 to_eye_w{0.0f, 0.0f, 1.0f};
};

// Fixed-point steps for the ball's own parallax: the error after k is
// (R / |g - c|)^k of the first, under 1e-3 rad for k = 3 at the rig's sizes.
constexpr int kNearFloorBallSteps = 3;

// From a surface point (z >= 0, W metres) along unit direction_w.
NearFloorLookup nearFloorLookup(const glm::vec3& point_w, const glm::vec3& direction_w, const NearFloorBall& ball);

// How much the camera's frame is trusted at a pixel (OpenCV's convention:
// centres at integers): 1 from kCameraFloorMarginPx inside the frame's
// edge, falling linearly to 0 at the edge, 0 outside.
constexpr float kCameraFloorMarginPx = 8.0f;
float cameraFloorWeight(const glm::vec2& pixel, int width_px, int height_px);

// How far from the axis (x^2 + y^2 of a point's undistorted (x/z, y/z)) a
// ground point may lie for the frame to be read there: 1.5 times the
// frame's own reach in each direction (its corners' rays). Further out the
// distortion polynomial is past its calibrated range and can fold a point
// far outside the frame back into it.
double cameraFloorReach2(const CameraIntrinsics& camera);

}  // namespace probelight::ibl
