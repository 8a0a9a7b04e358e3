// An exposure bracket of the ball turned into an HDR reflection map, with
// each frame checked first: the same steps for `analyze --bracket` (frames
// from files) and for `run` (frames the camera took at a recalibration).
#pragma once

#include <cmath>
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
#include "tracking/tag_tracker.hpp"

namespace probelight {

// Each bracket frame is merged through its own pose (ibl::bracketToCubeMap),
// so a camera that moves a little between exposures (a hand held still) is
// fine. Further, the frames see the ball from different sides: its rim,
// where one pixel spans many degrees, falls on other directions in each,
// and the merge (which weighs codes, not resolution) degrades: in
// tests/app/analyze_test.cpp's sun and sky view, a frame whose ball moved
// 2.7 px kept the irradiance within the 5%, one that moved 21 px
// took it to 7.5%. A frame whose ball moved more than this fraction of its
// radius is refused; that also keeps valid each frame's check of its
// exposure against the frame before (pixel against pixel).
constexpr double kBracketMaxBallShiftRadii = 0.1;
// Below this the frame is taken to be where the reference is: a tag seen
// in good light puts the ball within a few hundredths of a pixel, but at a
// short exposure the tag is dim and its pose scatters by up to half a
// pixel (measured on the simulator), which would misplace a sun more than
// a still camera does.
constexpr double kBracketPoseNoisePx = 1.0;
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
  double time_s = NAN;  // when the camera took it (not finite: unknown, as for files)
};

struct BracketSetup {
  ibl::MirrorBallView view;        // the reference frame's
  ibl::ProbeOutline outline;       // ... and its ball outline
  RigGeometry rig;
  tracking::TagDetectorSettings detector;
  ibl::HdrMergeSettings merge;
  int face_size = 64;
  // A frame whose tag is too dark to find: true, it takes the pose of the
  // frame before it (frames in the order the camera took them, as `run`
  // takes a bracket); false, the reference's (files said to show the same
  // view, in no known order).
  bool untracked_take_previous_pose = false;
  // A tracker of this rig and camera to follow the tag through the frames
  // (it is seeded with the reference's pose); null: one is made (building a
  // tag family's decode tables costs tens of milliseconds, so a kiosk keeps
  // one for all its brackets).
  tracking::TagTracker* tracker = nullptr;
  // When the camera took the reference frame, on the candidates' clock.
  // With it (and theirs), a camera that moved through the bracket beyond
  // the pose's noise is followed: a frame too dark to show the tag takes the
  // pose of the motion the others show (stages/bracket_motion.hpp).
  double reference_time_s = NAN;
};

struct BracketMergeResult {
  nlohmann::json frames = nlohmann::json::array();  // each candidate: label, ev, used, reason | pose, measured_ev
  std::optional<ibl::CubeMapRGB> hdr_cube;           // empty when no candidate was usable
  double still_clipped_sr = 0.0;  // directions clipped even in the shortest exposure
  std::vector<std::uint8_t> still_clipped;  // per texel of hdr_cube, 1 where so (a lower bound)
  std::string status;
  int used = 0;
};

// Checks each candidate (brightest first, each against the one before it,
// with which it shares the most well-exposed pixels) and leaves out, with
// its reason, those whose ball is all clipped or all black, whose tag puts
// the ball further than kBracketMaxBallShiftRadii of its radius from the
// reference's, or whose pixels
// disagree with its EV; `refused` is told of each. The rest are merged
// with the reference direction by direction, each through its own pose
// (ibl::bracketToCubeMap, up to 4 x 4 directions a texel: a sun smaller
// than a rim pixel is caught, not hit or missed). A frame whose tag is too
// dark to find takes a pose as setup.untracked_take_previous_pose says, or,
// where the frames' times are known and the tagged ones show the camera
// moving beyond the pose's noise, the pose that motion puts it at.
BracketMergeResult mergeBracketProbe(const ImageRGB8& reference, std::vector<BracketCandidate> candidates,
                                     const BracketSetup& setup,
                                     const std::function<void(const BracketCandidate&, const std::string&)>& refused);

}  // namespace probelight
