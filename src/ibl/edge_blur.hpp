// The frame's blur, measured where the frame has an edge that is sharp by
// construction: the printed tag's border against its white ring (the
// detected square's four sides). Each pixel near a side is put at its
// distance across the edge through the pose (its ray met with the tag's
// plane), in pixels of the image there, and its linear light normalised
// between the two inks' levels; a step blurred by a Gaussian,
// Phi((d - e) / s), fitted to those samples, gives the edge's spread s.
// What the lens, the sensor's pixel area and any processing did to the
// frame is all in s: the width a virtual object's edges need to look
// alike. e, fitted per side, takes the pose's error across the edge.
//
// A pixel's area alone gives a sharp edge a spread of 1/12 px^2 (a box of
// one pixel along any direction); lens_sigma_px is what is left besides it,
// the blur a renderer whose edges already have a pixel's coverage
// (anti-aliased) must add.
#pragma once

#include <string>

#include "core/types.hpp"
#include "ibl/color_transfer.hpp"
#include "ibl/white_reference.hpp"

namespace probelight::ibl {

struct EdgeBlurSettings {
  CameraTransfer camera_transfer;
  // Samples up to this far across the edge, and at most 0.45 of a cell
  // (the ring on one side and the border on the other are a cell wide).
  double max_reach_px = 6.0;
  // The middle of each side: its corners have two edges.
  double side_middle_fraction = 0.6;
  // A side needs this many samples and a reach of at least this many pixels
  // (three sigmas of a one-pixel blur).
  int min_samples_per_side = 24;
  double min_reach_px = 3.0;
  // The two levels must differ by this much linear light (of 1), and each
  // side's fit must leave a residual under this share of the step (a
  // shadow's edge, or something standing on the tag, does not).
  double min_step = 0.05;
  double max_rms_residual = 0.12;
};

enum class EdgeBlurStatus { kMeasured, kNotInView, kTooSmall, kNoEdge };
const char* toString(EdgeBlurStatus status);

struct EdgeBlurReading {
  EdgeBlurStatus status = EdgeBlurStatus::kNotInView;
  std::string message;
  double edge_sigma_px = 0.0;   // the spread s, pooled over the sides (rms)
  double lens_sigma_px = 0.0;   // sqrt(max(s^2 - 1/12, 0))
  double ten_to_ninety_px = 0.0;  // 2 x 1.2816 s: the edge's 10-90% width
  int sides = 0;
  long samples = 0;
};

// `border_half_m`: half the detected square (tag_size / 2); `cell_m` a
// cell's size. The tag in W: centred on the origin in z = 0, sides along X
// and Y.
EdgeBlurReading measureEdgeBlur(const CameraIntrinsics& camera, const PoseCamFromWorld& pose, double border_half_m,
                                double cell_m, const RgbPixelReader& read_pixel, const EdgeBlurSettings& settings);

}  // namespace probelight::ibl
