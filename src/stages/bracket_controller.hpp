// The exposure bracket of a recalibration, as a pure unit: which exposures to
// ask the camera for and when, which frames are rungs of the ladder, when the
// bracket is over, and when the camera is back at its exposure after it.
// Driven by each frame's exposure (its metadata) and by the recalibration's
// progress; it reaches the camera only through ExposureControl, and counts
// what happened into a RunReport. The frames' pixels (what is merged) stay
// with the caller: it is told which frames to keep, and asked (through a
// callback) whether a frame's ball still clips.
//
// The sequence (lights.bracket_*):
//   - A recalibration whose ball clips asks for its ladder a few frames
//     before the fit frame (leadTheLadder): the camera's latency less one,
//     learnt from the last bracket's first rung, 2 to begin with (libcamera
//     queues requests ahead, and sensors apply exposure two frames late), so
//     that the latency passes while the recalibration still counts good
//     frames at the normal exposure and the rungs follow the fit frame at
//     once. A rung that arrives before the fit frame (a camera quicker than
//     that) calls the early ladder off: that frame is darker than the fit's
//     should be, and the fit asks again.
//   - At the fit frame (start), when its ball clips, the bracket begins: the
//     early ladder's rungs are adopted, or the whole ladder is asked for now.
//     The rungs: -step, -2 step, ... down to -max_stops, gain down to 1 first,
//     then exposure time; the ones below the sensor's shortest exposure
//     (where the camera says it) replaced by that one exposure.
//   - Each frame of the bracket (arrive): a frame at least 2 x 0.25 stops
//     shorter than the last one kept is kept as a rung. The bracket is over at
//     the first rung whose ball no longer clips or that is the ladder's last,
//     on the third frame after a rung with none shorter (a sensor that went
//     no shorter than it said), or on the ninth with no rung at all.
//   - After it (finish), frames still in flight at bracket exposures are not
//     shown (settling) until one is back within 0.25 stops of the exposure
//     before the bracket, or eight frames have been held back. After an early
//     ladder called off, its rungs already begun may still come after frames
//     at the normal exposure: for eight frames, a frame more than 0.25 stops
//     darker than that exposure is held back, the others shown.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "capture/exposure_control.hpp"
#include "stages/run_report.hpp"

namespace probelight {

using ManualExposure = ExposureControl::ManualExposure;

struct BracketSettings {
  double step_stops = 3.0;   // lights.bracket_step_stops
  double max_stops = 12.0;   // lights.bracket_max_stops; 0: no bracket
};

// A frame's exposure as its metadata says: exposure_us 0 when the source
// cannot say, analogue_gain 0 when it cannot say (taken as 1).
struct FrameExposure {
  double exposure_us = 0.0;
  double analogue_gain = 0.0;
};

// The rungs of a bracket: their EVs (stops from the exposure they were
// planned from) and the exposures asked for.
struct ExposureLadder {
  std::vector<double> ev;
  bool at_shortest = false;  // its last rung is the sensor's shortest exposure
  std::vector<ManualExposure> exposures;
};

// Where a recalibration stands (LightingStateMachine's view of it).
struct RecalibrationProgress {
  bool recalibrating = false;
  int good_frames = 0;         // consecutive good frames so far
  int good_frames_needed = 5;  // the fit comes at this many
};

// What an arriving frame is.
enum class FrameRole {
  kPipeline,  // an ordinary frame: the pipeline runs on it
  kBracket,   // a frame of a bracket being taken: not shown
  kSettling,  // just after a bracket, still at a bracket exposure: not shown
};

struct FrameArrival {
  FrameRole role = FrameRole::kPipeline;
  // kBracket: keep this frame for the merge, at rung_ev stops from the fit
  // frame's exposure.
  bool keep_as_rung = false;
  double rung_ev = 0.0;
  // kBracket: the bracket is over with this frame: call finish() and merge.
  bool bracket_over = false;
  // kBracket, with bracket_over: no rung came in kMaxWaitFrames (the caller
  // says so: the ladder's first EV is in the record).
  bool not_delivered = false;
};

// Why start() did not begin a bracket (kStarted: it did).
enum class BracketStart {
  kStarted,
  kOff,                    // max_stops is 0
  kBallNotInView,          // no ball outline in the fit frame (its tag was not found)
  kNoExposureMetadata,     // the fit frame does not say its exposure: no EV could be told
  kNotNeeded,              // nothing clipped: the 8-bit map holds all the light
  kAtShortestExposure,     // the fit frame was already as short as the sensor goes
  kUnsupported,            // the camera has no exposure control
};

// A bracket as it ended, for the report.
struct BracketRecord {
  ExposureLadder ladder;         // the rungs asked for, EVs from `base`
  ManualExposure base;           // the fit frame's exposure
  std::uint64_t started_frame = 0;
  int lead_frames = 0;           // the ladder was asked for this many frames before the fit frame
  int latency_frames = -1;       // from the request to its first rung (-1: none came)
  std::vector<double> rung_ev;   // the rungs kept, in order
};

class BracketController {
 public:
  // A requested exposure shows in a frame's metadata within a few frames;
  // past this the bracket ends with what it has (and settling gives up).
  static constexpr int kMaxWaitFrames = 8;
  // A frame counts as a rung, or as back, within this many stops of it
  // (sensors round exposure time to whole lines).
  static constexpr double kEvMatchStops = 0.25;
  // A frame is kept when it is at least this much shorter than the last one
  // kept: it shows something the others clipped. (A frame caught between
  // rungs, where a sensor applies gain a frame before exposure time, is kept
  // too: its metadata says the exposure it had.)
  static constexpr double kNewRungStops = 2.0 * kEvMatchStops;
  // Once rungs have begun they come one a frame: this many frames with none
  // shorter is a sensor that went no shorter than it said.
  static constexpr int kClampedAfterFrames = 3;
  static constexpr int kMaxLeadFrames = 6;
  static constexpr int kInitialLeadFrames = 2;

  BracketController(BracketSettings settings, ExposureControl& camera, RunReport& report);

  // Every frame, before anything else. `ball_clips` says whether this
  // frame's ball (as the fit frame's outline places it) has clipped pixels;
  // it is asked only for a frame that becomes a rung.
  FrameArrival arrive(const FrameExposure& frame, std::uint64_t frame_number,
                      const std::function<bool()>& ball_clips);

  // Each frame of a recalibration that did not end it (FrameOutcome::kNothing):
  // asks for the ladder lead frames before the fit frame when `ball_in_view`
  // and the ball clips; calls an early ladder off when the count started over.
  // Nothing while a bracket is pending.
  void leadTheLadder(const FrameExposure& frame, std::uint64_t frame_number, const RecalibrationProgress& progress,
                     bool ball_in_view, const std::function<bool()>& ball_clips);

  // The fit frame: begins a bracket when `ball_in_view` and its ball clips.
  // Not begun (anything but kStarted), the fit goes on without one: call
  // fitWithoutBracket().
  BracketStart start(const FrameExposure& frame, std::uint64_t frame_number, bool ball_in_view,
                     const std::function<bool()>& ball_clips);
  // A fit that takes no bracket (none needed, or the recalibration gave up):
  // an early ladder still out is called off.
  void fitWithoutBracket();

  // Ends the bracket (arrive said it is over, the run ended, the camera was
  // lost): the camera goes back to what it had, frames settle, and the record
  // says what was asked and kept.
  BracketRecord finish();

  // The camera was lost: its new stream starts at its own exposure, and
  // asks for a ladder afresh. A bracket still pending stays, to be finished
  // (counted as brackets_cut_by_camera_loss).
  void onCameraLost();

  bool pending() const { return pending_.has_value(); }
  // The pending bracket's ladder (null when none is pending).
  const ExposureLadder* pendingLadder() const { return pending_ ? &pending_->ladder : nullptr; }
  bool earlyLadderOut() const { return early_.has_value(); }
  bool settling() const { return settling_.has_value(); }
  int leadFrames() const { return lead_frames_; }

  // The rungs for a bracket from `base` (exposed for tests).
  ExposureLadder planLadder(const ManualExposure& base) const;

 private:
  struct Pending {
    ExposureLadder ladder;
    ManualExposure base;
    std::uint64_t started_frame = 0;
    int lead_frames = 0;
    int latency_frames = -1;
    int frames_waited = 0;  // since the start, or since the last rung kept
    std::vector<double> rung_ev;
  };
  struct Early {
    ManualExposure base;
    ExposureLadder ladder;
    std::uint64_t requested_frame = 0;
  };
  struct Settling {
    ManualExposure base;  // the exposure to come back to
    int frames_waited = 0;
    // An early ladder called off: its rungs already begun may still come,
    // after frames at the base (held back as they come, for kMaxWaitFrames).
    bool rungs_may_follow = false;
  };

  FrameArrival bracketFrame(const FrameExposure& frame, std::uint64_t frame_number,
                            const std::function<bool()>& ball_clips);
  void cancelEarly(const char* counter);

  BracketSettings settings_;
  ExposureControl& camera_;
  RunReport& report_;
  std::optional<Pending> pending_;
  std::optional<Early> early_;
  std::optional<Settling> settling_;
  int lead_frames_ = kInitialLeadFrames;
};

}  // namespace probelight
