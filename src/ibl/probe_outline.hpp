// Where the mirror ball appears in the image, from the pose and the rig.
// Under perspective a sphere's image is not a circle around its projected
// centre: the outline is the image of the circle where the tangent cone from
// the camera centre touches the sphere (an ellipse, bent further by lens
// distortion). This is the pipeline's own computation; the simulator has an
// independent one for its truth.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "ibl/mirror_ball.hpp"

namespace probelight::ibl {

struct ProbeOutline {
  bool valid = false;             // false when the camera is inside or behind the ball, or on non-finite input
  glm::dvec2 center_px{0.0};      // area centroid of the outline
  double radius_px = 0.0;         // radius of the circle with the outline's area
  glm::dvec2 min_px{0.0};         // bounding box of the outline
  glm::dvec2 max_px{0.0};
  bool fully_in_image = false;    // every outline point lies inside the image
  std::vector<glm::dvec2> polygon_px;  // the outline itself, for drawing (empty when invalid)
};

// `samples` points around the tangency circle, projected with distortion;
// centroid and area by the shoelace formula. 128 samples put the polygon's
// area within 0.04% of the ellipse's (1 - sin(2pi/n)/(2pi/n)).
ProbeOutline computeProbeOutline(const MirrorBallView& view, int samples = 128);

}  // namespace probelight::ibl
