// Refines the mirror ball's outline against the edges in the image, to
// absorb error in the rig's measured ball position or radius.
//
// The predicted outline (ibl::computeProbeOutline, from the pose and the rig)
// is the model; the image shows where the ball's silhouette really is. Along
// the outward normal at each of `samples` points of the outline, a profile of
// linear light is read across the silhouette from the outside in. At the
// silhouette the ball reflects what lies just behind it, the background
// beside it, darkened by the ball's reflectance; so the edge is where the
// light first falls halfway from the background's level to reflectance times
// it (for a step blurred by a symmetric kernel, the half-level crossing is
// the step's position). The adjusted outline is the predicted one shifted by
// d and scaled by s about its centre, q = c + s (p - c) + d; each edge gives
// one linear equation in (d, s - 1) (its offset along the normal), solved by
// least squares with Huber weights.
//
// A profile is trusted when the step (1 - reflectance) x background is at
// least min_relative_step of the background, the light crosses the half level
// within the search range, and the background outside is level (texture or
// another edge there would move the crossing); with too few trusted profiles
// there is no fit. A perfect mirror (reflectance 1) shows no step at its rim,
// and cannot be refined. Just inside the rim the ball already reflects light
// from centimetres away, so a fit is good to a few tenths of a pixel (0.28 px
// at worst in tests/tracking/probe_edge_fit_test.cpp): worth it against a rig
// measured millimetres wrong, not against a correct one.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/probe_outline.hpp"

namespace probelight::tracking {

struct ProbeEdgeFitSettings {
  int samples = 96;               // profiles around the outline
  double search_px = 4.0;         // how far each profile reaches on either side of the predicted outline
  double min_trusted_fraction = 0.4;  // of the profiles, for a fit
  // 5%: eight times the noise of a 1.5-code sensor at mid grey in linear light.
  double min_relative_step = 0.05;
  double max_rms_px = 0.5;        // a fit whose edges scatter more than this is refused
};

struct ProbeEdgeFit {
  bool ok = false;
  std::string reason;             // why not, when !ok
  glm::dvec2 shift_px{0.0};       // d
  double radius_scale = 1.0;      // s
  glm::dvec2 center_px{0.0};      // of the adjusted outline (predicted centre + d)
  double radius_px = 0.0;         // predicted radius * s
  int profiles = 0;               // read
  int trusted_profiles = 0;       // with a clear step, used in the fit
  double rms_px = 0.0;            // of the trusted edges about the adjusted outline
};

// `outline`: the predicted outline (valid, fully in the image). `luma`: the
// 8-bit frame, decoded to linear light through `transfer`. Never throws.
ProbeEdgeFit fitProbeOutlineToEdges(const std::uint8_t* luma, int width, int height, int stride_bytes,
                                    const ibl::ProbeOutline& outline, double probe_reflectance,
                                    const ibl::CameraTransfer& transfer, const ProbeEdgeFitSettings& settings = {});

// The ball centre in W that moves the ball's image by `shift_px` at the
// current pose: the shift taken perpendicular to the line of sight at the
// ball's depth (a radius_scale is a size error, not a position one, and is
// not turned into a move). For turning per-frame fits into a rig correction.
glm::dvec3 probeCenterForImageShift(const PoseCamFromWorld& pose, const CameraIntrinsics& camera,
                                    const glm::dvec3& probe_center_w, const glm::dvec2& shift_px);

}  // namespace probelight::tracking
