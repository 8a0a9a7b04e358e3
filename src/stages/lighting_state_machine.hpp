// The main loop's two states: running, and recalibrating the lights. Pure
// logic, driven by button presses and processed frames, so it can be tested
// with synthetic event sequences.
#pragma once

#include <string>

namespace probelight {

enum class AppState { kRunning, kRecalibrating };

struct RecalibrationPolicy {
  // Consecutive frames in which the ball was seen well before the lights are
  // fitted: one frame could be a bad one (motion blur, a hand in front).
  int good_frames_needed = 5;
  // Frames after which a recalibration that never saw the ball gives up and
  // keeps the previous lighting.
  int max_frames = 150;
};

enum class FrameOutcome {
  kNothing,          // keep going
  kFitLights,        // this frame completes a recalibration: fit the lights from the current maps
  kCalibrationFailed  // gave up: the last good lighting stays
};

class LightingStateMachine {
 public:
  // The kiosk calibrates at start-up, so it begins in kRecalibrating.
  explicit LightingStateMachine(RecalibrationPolicy policy = {});

  AppState state() const { return state_; }
  // A press while running starts a recalibration. A press during one is
  // ignored (it would only restart the same measurement) and counted.
  void onButtonPress();
  // probe_usable: the tag was found and the ball's maps were updated from
  // this frame.
  FrameOutcome onFrame(bool probe_usable);

  int pressesAccepted() const { return presses_accepted_; }
  int pressesIgnored() const { return presses_ignored_; }
  int calibrationsCompleted() const { return calibrations_completed_; }
  int calibrationsFailed() const { return calibrations_failed_; }
  int goodFramesSoFar() const { return good_frames_; }
  const RecalibrationPolicy& policy() const { return policy_; }

 private:
  RecalibrationPolicy policy_;
  AppState state_ = AppState::kRecalibrating;
  int good_frames_ = 0;
  int frames_in_calibration_ = 0;
  int presses_accepted_ = 0;
  int presses_ignored_ = 0;
  int calibrations_completed_ = 0;
  int calibrations_failed_ = 0;
};

const char* toString(AppState state);

}  // namespace probelight
