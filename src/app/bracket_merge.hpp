// An exposure bracket of the ball turned into an HDR reflection map, with
// each frame checked first: the same steps for `analyze --bracket` (frames
// from files) and for `run` (frames the camera took at a recalibration).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/types.hpp"
#include "ibl/cube_map.hpp"
#include "ibl/hdr_bracket.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_outline.hpp"
#include "tracking/tag_detector.hpp"

namespace probelight {

// A bracket frame whose ball sits further than this from the reference
// frame's (the camera or the rig moved between exposures) would smear every
// edge of the merged map; tag poses agree to a few hundredths of a pixel
// when nothing moved.
constexpr double kBracketMaxBallShiftPx = 1.0;
// A frame whose pixels say another exposure than its label by more than
// this many stops is refused: its EV is wrong, or the light changed.
constexpr double kBracketMaxEvDisagreement = 0.5;

struct BallPixelCodes {
  long measured = 0;  // ball pixels with every channel between dark and clip
  long clipped = 0;   // ... with some channel clipped
};
// Over the pixels inside the ball's outline (its bounding box, inside the
// circle of its area-equivalent radius).
BallPixelCodes ballPixelCodes(const ImageRGB8& image, const ibl::ProbeOutline& outline,
                              const ibl::HdrMergeSettings& merge);

struct BracketCandidate {
  std::string label;  // a file name, or "camera frame 12"
  double ev = 0.0;    // stops from the reference exposure (< 0: shorter)
  ImageRGB8 rgb;      // the reference's size
};

struct BracketSetup {
  ibl::MirrorBallView view;        // the reference frame's
  ibl::ProbeOutline outline;       // ... and its ball outline
  RigGeometry rig;
  tracking::TagDetectorSettings detector;
  ibl::HdrMergeSettings merge;
  int face_size = 64;
};

struct BracketMergeResult {
  nlohmann::json frames = nlohmann::json::array();  // each candidate: label, ev, used, reason | pose, measured_ev
  std::optional<ibl::CubeMapRGB> hdr_cube;           // empty when no candidate was usable
  long still_clipped_ball_px = 0;
  std::string status;
  int used = 0;
};

// Checks each candidate (brightest first, each against the one before it,
// with which it shares the most well-exposed pixels) and leaves out, with
// its reason, those whose ball is all clipped or all black, whose tag puts
// the ball more than kBracketMaxBallShiftPx from the reference's (where the
// tag is bright enough to be found), or whose pixels disagree with its EV;
// `refused` is told of each. The rest are merged with the reference
// (ibl::mergeBracket) and projected into a cube map with 4 x 4 directions
// per texel (a sun smaller than a rim pixel is caught, not hit or missed).
BracketMergeResult mergeBracketProbe(const ImageRGB8& reference, std::vector<BracketCandidate> candidates,
                                     const BracketSetup& setup,
                                     const std::function<void(const BracketCandidate&, const std::string&)>& refused);

}  // namespace probelight
