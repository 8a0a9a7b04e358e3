// What one frame carries through the stages: each stage reads what the
// stages before it wrote and adds its own part. Nothing here outlives the
// frame; what does (the maps, the lights, the shadow maps) stays with the
// stage that made it.
//
//   capture -> upload -> track -> maps -> lights -> shadows -> compose -> display
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "capture/frame_source.hpp"
#include "ibl/mirror_ball.hpp"
#include "ibl/probe_outline.hpp"
#include "stages/map_update_policy.hpp"
#include "tracking/probe_edge_fit.hpp"
#include "tracking/tag_tracker.hpp"

namespace probelight {

struct FrameContext {
  FrameContext(const FrameBuffer& frame_in, std::uint64_t number_in)
      : frame(frame_in), number(number_in), time_s(static_cast<double>(frame_in.metadata.timestamp_ns) * 1e-9) {}

  // capture
  const FrameBuffer& frame;
  std::uint64_t number = 0;  // frames processed before this one
  double time_s = 0.0;       // from the frame's timestamp
  std::uint64_t frames_since_camera_start = 0;  // this one included (auto exposure converges over the first)

  // track: the tag, its pose (smoothed where smoothing is on), and the ball.
  tracking::TagTrackResult track;
  // The tracker's own pose, when smoothing replaced it in `track`.
  std::optional<ibl::MirrorBallView> unsmoothed_view;
  ibl::MirrorBallView view;     // the ball seen through `track.pose` (rig.yaml's, as probe refinement corrects it)
  ibl::ProbeOutline outline;    // valid only when the tag was found
  // The ball's outline fitted to the image, when the track stage fitted it
  // (probe refinement, or when asked to for a report).
  std::optional<tracking::ProbeEdgeFit> probe_edge_fit;

  // maps
  MapUpdateDecision map_decision;
  bool maps_updated = false;  // this frame remade the maps
  bool maps_current = false;  // the maps hold this frame's ball: remade, or its image matched them

  // What the status bar says (empty: nothing to say). Each stage may set or
  // extend it.
  std::string status;
};

}  // namespace probelight
