#include "stages/bracket_controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace probelight {

namespace {

// A frame's exposure, gain 1 where the metadata does not say.
ManualExposure exposureOf(const FrameExposure& frame) {
  return {frame.exposure_us, frame.analogue_gain > 0.0 ? frame.analogue_gain : 1.0};
}

// Stops of a frame's exposure from `base` (NaN when it does not say).
double stopsFrom(const FrameExposure& frame, const ManualExposure& base) {
  if (!(frame.exposure_us > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const ManualExposure exposure = exposureOf(frame);
  return std::log2(exposure.exposure_us * exposure.analogue_gain / (base.exposure_us * base.analogue_gain));
}

// Shorter by `ev` stops: the gain comes down to 1 first (any sensor takes
// it, and it adds noise), then the exposure time, which sensors bound below.
ManualExposure exposureAt(const ManualExposure& base, double ev) {
  const double gain = std::min(base.analogue_gain, 1.0);
  return {base.exposure_us * base.analogue_gain / gain * std::exp2(ev), gain};
}

}  // namespace

BracketController::BracketController(BracketSettings settings, ExposureControl& camera, RunReport& report)
    : settings_(settings), camera_(camera), report_(report) {}

// The rungs -step, -2 step, ... down to -max_stops, the ones below the
// sensor's shortest exposure (where the camera knows it) replaced by that
// one exposure, and that one left out when it is hardly shorter than the
// rung before it.
ExposureLadder BracketController::planLadder(const ManualExposure& base) const {
  const std::optional<double> shortest_us = camera_.shortestExposureUs();
  ExposureLadder ladder;
  for (double ev = -settings_.step_stops; ev >= -settings_.max_stops - 1e-9; ev -= settings_.step_stops) {
    ManualExposure exposure = exposureAt(base, ev);
    if (shortest_us && exposure.exposure_us < *shortest_us) {
      exposure.exposure_us = *shortest_us;
      const double shortest_ev =
          std::log2(exposure.exposure_us * exposure.analogue_gain / (base.exposure_us * base.analogue_gain));
      const double previous_ev = ladder.ev.empty() ? 0.0 : ladder.ev.back();
      if (shortest_ev <= previous_ev - kNewRungStops) {
        ladder.ev.push_back(shortest_ev);
        ladder.exposures.push_back(exposure);
      }
      ladder.at_shortest = true;
      break;
    }
    ladder.ev.push_back(ev);
    ladder.exposures.push_back(exposure);
  }
  return ladder;
}

FrameArrival BracketController::arrive(const FrameExposure& frame, std::uint64_t frame_number,
                                       const std::function<bool()>& ball_clips) {
  if (pending_) return bracketFrame(frame, frame_number, ball_clips);
  if (early_) {
    // The camera is quicker than the lead assumed: this frame is darker
    // than the fit's should be. Called off; the fit asks again.
    const double ev = stopsFrom(frame, early_->base);
    if (std::isfinite(ev) && ev < -kEvMatchStops) {
      cancelEarly("bracket_early_ladders_too_early");
      lead_frames_ = 0;
    }
  }
  if (settling_) {
    const double ev = stopsFrom(frame, settling_->base);
    if (settling_->rungs_may_follow) {
      // A ladder called off before (all) its rungs came: those already
      // begun still arrive, after frames at the normal exposure. For as long
      // as they can, a frame darker than the base is one of them.
      if (!std::isfinite(ev) || ++settling_->frames_waited > kMaxWaitFrames) {
        settling_.reset();
      } else if (ev < -kEvMatchStops) {
        return {FrameRole::kSettling};
      }
      return {FrameRole::kPipeline};
    }
    // Back once a frame is at the exposure from before (or after
    // kMaxWaitFrames, when the camera's AE has moved on).
    if (!std::isfinite(ev) || std::abs(ev) <= kEvMatchStops || ++settling_->frames_waited > kMaxWaitFrames)
      settling_.reset();
    else
      return {FrameRole::kSettling};
  }
  return {FrameRole::kPipeline};
}

FrameArrival BracketController::bracketFrame(const FrameExposure& frame, std::uint64_t frame_number,
                                             const std::function<bool()>& ball_clips) {
  Pending& bracket = *pending_;
  FrameArrival arrival{FrameRole::kBracket};
  const double ev = stopsFrom(frame, bracket.base);
  const double last_ev = bracket.rung_ev.empty() ? 0.0 : bracket.rung_ev.back();
  if (std::isfinite(ev) && ev <= last_ev - kNewRungStops) {
    // The camera's latency, learnt from its first rung: later brackets ask
    // for their ladder that many frames (less one) before the fit.
    if (bracket.rung_ev.empty()) {
      bracket.latency_frames = static_cast<int>(frame_number - bracket.started_frame) + bracket.lead_frames;
      lead_frames_ = std::clamp(bracket.latency_frames - 1, 0, kMaxLeadFrames);
    }
    const bool still_clips = ball_clips();
    bracket.rung_ev.push_back(ev);
    bracket.frames_waited = 0;
    report_.count("bracket_frames");
    arrival.keep_as_rung = true;
    arrival.rung_ev = ev;
    const bool ladder_done = ev <= bracket.ladder.ev.back() + kEvMatchStops;
    // The sensor's shortest exposure and the ball still clips: asking for
    // less would give the same again.
    if (still_clips && ladder_done && bracket.ladder.at_shortest) report_.count("bracket_exposures_clamped");
    arrival.bracket_over = !still_clips || ladder_done;
  } else if (!bracket.rung_ev.empty()) {
    if (++bracket.frames_waited >= kClampedAfterFrames) {
      report_.count("bracket_exposures_clamped");  // a limit the camera did not tell
      arrival.bracket_over = true;
    }
  } else if (++bracket.frames_waited > kMaxWaitFrames) {
    report_.count("bracket_exposures_not_delivered");
    arrival.bracket_over = true;
    arrival.not_delivered = true;
  }
  return arrival;
}

void BracketController::leadTheLadder(const FrameExposure& frame, std::uint64_t frame_number,
                                      const RecalibrationProgress& progress, bool ball_in_view,
                                      const std::function<bool()>& ball_clips) {
  if (pending_) return;  // its own ladder is out: a new one would replace its rungs
  const int needed = progress.good_frames_needed;
  const int lead = std::min(lead_frames_, needed - 1);
  if (early_) {
    // The count started over (the ball was lost): not this time.
    if (!progress.recalibrating || progress.good_frames < needed - lead) cancelEarly("bracket_early_ladders_unused");
    return;
  }
  if (lead <= 0 || !progress.recalibrating || progress.good_frames != needed - lead || !ball_in_view ||
      !(settings_.max_stops > 0.0) || !(frame.exposure_us > 0.0))
    return;
  if (!ball_clips()) return;
  Early early{exposureOf(frame), {}, frame_number};
  early.ladder = planLadder(early.base);
  if (early.ladder.exposures.empty() || !camera_.setExposureLadder(early.ladder.exposures)) return;  // start() says why
  early_ = std::move(early);
  report_.count("bracket_early_ladders");
}

BracketStart BracketController::start(const FrameExposure& frame, std::uint64_t frame_number, bool ball_in_view,
                                      const std::function<bool()>& ball_clips) {
  if (!(settings_.max_stops > 0.0)) return BracketStart::kOff;
  if (!ball_in_view) return BracketStart::kBallNotInView;
  if (!(frame.exposure_us > 0.0)) {
    report_.count("brackets_without_exposure_metadata");  // the EV of a frame could not be told
    return BracketStart::kNoExposureMetadata;
  }
  if (!ball_clips()) {
    report_.count("brackets_not_needed");  // nothing clipped: the 8-bit map holds all the light
    return BracketStart::kNotNeeded;
  }
  Pending bracket;
  bracket.base = exposureOf(frame);
  bracket.started_frame = frame_number;
  if (early_) {
    // Asked for a few frames ago: its rungs are on their way. Their EVs
    // from this frame's exposure (the same, with AE locked).
    const double shift = std::log2(early_->base.exposure_us * early_->base.analogue_gain /
                                   (bracket.base.exposure_us * bracket.base.analogue_gain));
    bracket.ladder = early_->ladder;
    for (double& ev : bracket.ladder.ev) ev += shift;
    bracket.lead_frames = static_cast<int>(frame_number - early_->requested_frame);
    early_.reset();
  } else {
    bracket.ladder = planLadder(bracket.base);
    if (bracket.ladder.exposures.empty()) {
      report_.count("brackets_at_shortest_exposure");  // the frame was already as short as the sensor goes
      return BracketStart::kAtShortestExposure;
    }
    if (!camera_.setExposureLadder(bracket.ladder.exposures)) {
      report_.count("brackets_unsupported");
      return BracketStart::kUnsupported;
    }
  }
  report_.count("brackets_started");
  pending_ = std::move(bracket);
  return BracketStart::kStarted;
}

void BracketController::fitWithoutBracket() {
  if (early_) cancelEarly("bracket_early_ladders_unused");
}

BracketRecord BracketController::finish() {
  Pending bracket = std::move(*pending_);
  pending_.reset();
  camera_.setExposureLadder({});
  settling_ = Settling{bracket.base, 0, false};
  return {std::move(bracket.ladder), bracket.base,          bracket.started_frame,
          bracket.lead_frames,       bracket.latency_frames, std::move(bracket.rung_ev)};
}

void BracketController::onCameraLost() {
  if (pending_) report_.count("brackets_cut_by_camera_loss");  // to be finished with what it has
  settling_.reset();  // a new stream starts at its own exposure
  early_.reset();     // ... and asks for a ladder afresh
}

void BracketController::cancelEarly(const char* counter) {
  camera_.setExposureLadder({});
  settling_ = Settling{early_->base, 0, true};
  early_.reset();
  report_.count(counter);
}

}  // namespace probelight
