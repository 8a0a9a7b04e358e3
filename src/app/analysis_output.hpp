// What `analyze` and `render` write for a person to check by eye:
// analysis.json laid out readably, overlay.png (the tag, the W axes and the
// ball's outline on the frame), ball.png (the ball, enlarged) and the cube
// maps unfolded as crosses (declared in analyze.hpp).
#pragma once

#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "core/types.hpp"
#include "ibl/probe_outline.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

using AnalysisJson = nlohmann::ordered_json;  // keys in the order written

// Indented JSON with vectors and matrices on one line each (nlohmann's dump
// puts every number on its own line, 20 lines for a 3x3 rotation).
std::string readableJson(const AnalysisJson& value, int indent = 0);

std::string formatFixed(double value, int decimals);

// overlay.png: the frame (BGR) with, where the tag was found, its outline
// (yellow) and the W axes (X red, Y green, Z blue, one tag long), the ball's
// outline and centre (magenta, when `outline` is given), and `caption` on a
// dark strip across the top (red-ish when `failed`).
cv::Mat overlayPicture(const cv::Mat& frame_bgr, const CameraIntrinsics& camera, const RigGeometry& rig,
                       const tracking::TagTrackResult& track, const ibl::ProbeOutline* outline,
                       const std::string& caption, bool failed);
// The overlay's own caption: the tag's family and id, and the ball's radius.
std::string overlayCaption(const RigGeometry& rig, const tracking::TagTrackResult& track,
                           const ibl::ProbeOutline* outline);

// ball.png: the ball's bounding box and a margin, each camera pixel a
// kBallZoom x kBallZoom block.
struct BallCrop {
  cv::Mat picture;
  cv::Rect crop_px;
};
// The ball is ~20-60 px across in a 640x480 frame; 4x nearest makes each
// camera pixel a visible block without resampling it.
inline constexpr int kBallZoom = 4;
BallCrop ballCropPicture(const cv::Mat& frame_bgr, const ibl::ProbeOutline& outline);

// The crosses: 128 px tiles hold a 64^2 reflection face as 2x2 blocks and a
// 32^2 diffuse face as 4x4 blocks.
inline constexpr int kCrossTilePx = 128;

}  // namespace probelight
