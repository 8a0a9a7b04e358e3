// Full-resolution refinement of a detected tag's four corners by fitting a
// straight line to each edge of the black border and intersecting the lines.
//
// Why: libapriltag finds the quad on a decimated image and its refine_edges
// step snaps to gradients of the sRGB-encoded luma. An anti-aliased or
// optically blurred edge is an average in *linear* light; in sRGB codes the
// ramp is no longer symmetric, so a gradient peak (or a 50%-code crossing)
// sits off the true edge toward the dark side. Each corner then carries a few
// tenths of a pixel of bias that no amount of averaging removes, and the pose
// inherits it.
//
// How (right by construction, no fitted constants):
// - each 8-bit luma sample is decoded to linear light before interpolation;
// - across the edge, the position of a blurred step is found from its area:
//   for a step from level w (outside) to b (inside) at offset e, blurred by
//   any kernel of unit area that fits inside the window [-R, R],
//   integral((L(s) - b) / (w - b)) ds = e + R exactly. This holds for the
//   pixel box (and the simulator's area-integrated edge pixels) and for lens blur alike,
//   symmetric or not;
// - the samples along each edge are undistorted, so the line fit is exact for
//   a pinhole camera after the lens model; corners = intersections of
//   adjacent lines, distorted back into the frame.
// One sample per pixel along each edge averages the sensor noise, so the
// corners rest on hundreds of pixels instead of the few around each corner.
// The same profiles are taken across every bit-cell boundary of the tag that
// shows a step (found by contrast, so the code need not be known); those
// points, at known places on the tag, go to the pose refinement in
// TagTracker (tag_tracker.cpp, refineOnEdgePoints).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"

namespace probelight::tracking {

struct CornerRefineSettings {
  // How far a refined corner may move from the detection before the
  // refinement is distrusted (the detector's corners are within ~1 px).
  double max_shift_px = 2.0;
  int passes = 2;  // the second pass samples along the edges the first one found
};

// A point found on a step edge of the tag, undistorted pixels (P = K), and
// the tag-grid segment it lies on, in unit tag coordinates: (-1,-1), (1,-1),
// (1,1), (-1,1) are world corners 0..3, so W = (q * tag_size / 2, 0).
struct TagEdgePoint {
  glm::dvec2 undistorted_px{0.0};
  glm::dvec2 segment_a{0.0}, segment_b{0.0};
};

struct RefinedTagCorners {
  std::array<glm::dvec2, 4> corners_px{};
  // The outer edges' points and every bit-cell boundary found with a step
  // (the code need not be known): more measurements for the pose.
  std::vector<TagEdgePoint> edge_points;
};

// `corners_px`: corner k = image of world corner k, OpenCV pixel centres,
// distorted. Returns refined corners in the same convention, or nothing when
// an edge lacks contrast or the fit moved a corner too far. Never throws.
// `border_width_cells`: the family's width_at_border (8 for tag36h11): the
// quad's side in cells, so one cell of black border lies inside each edge.
std::optional<RefinedTagCorners> refineTagCorners(const std::uint8_t* luma, int width, int height, int stride_bytes,
                                                  const std::array<glm::dvec2, 4>& corners_px,
                                                  const CameraIntrinsics& camera, int border_width_cells,
                                                  const CornerRefineSettings& settings = {});

}  // namespace probelight::tracking
