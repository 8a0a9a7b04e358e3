#include "stages/lighting_state_machine.hpp"

namespace probelight {

LightingStateMachine::LightingStateMachine(RecalibrationPolicy policy) : policy_(policy) {
  if (policy_.good_frames_needed < 1) policy_.good_frames_needed = 1;
  if (policy_.max_frames < policy_.good_frames_needed) policy_.max_frames = policy_.good_frames_needed;
}

void LightingStateMachine::onButtonPress() {
  if (state_ == AppState::kRecalibrating) {
    ++presses_ignored_;
    return;
  }
  ++presses_accepted_;
  state_ = AppState::kRecalibrating;
  good_frames_ = 0;
  frames_in_calibration_ = 0;
}

FrameOutcome LightingStateMachine::onFrame(bool probe_usable) {
  if (state_ != AppState::kRecalibrating) return FrameOutcome::kNothing;
  ++frames_in_calibration_;
  good_frames_ = probe_usable ? good_frames_ + 1 : 0;
  if (good_frames_ >= policy_.good_frames_needed) {
    state_ = AppState::kRunning;
    ++calibrations_completed_;
    return FrameOutcome::kFitLights;
  }
  if (frames_in_calibration_ >= policy_.max_frames) {
    state_ = AppState::kRunning;
    ++calibrations_failed_;
    return FrameOutcome::kCalibrationFailed;
  }
  return FrameOutcome::kNothing;
}

const char* toString(AppState state) {
  return state == AppState::kRunning ? "running" : "recalibrating";
}

}  // namespace probelight
