#include <gtest/gtest.h>

#include "stages/lighting_state_machine.hpp"

namespace probelight {
namespace {

TEST(LightingStateMachine, StartsByCalibratingAndFitsAfterEnoughGoodFrames) {
  LightingStateMachine machine({.good_frames_needed = 3, .max_frames = 10});
  EXPECT_EQ(machine.state(), AppState::kRecalibrating);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kFitLights);
  EXPECT_EQ(machine.state(), AppState::kRunning);
  EXPECT_EQ(machine.calibrationsCompleted(), 1);
  // Running: frames do nothing.
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kNothing);
}

TEST(LightingStateMachine, BadFrameRestartsTheCountOfGoodOnes) {
  LightingStateMachine machine({.good_frames_needed = 3, .max_frames = 100});
  machine.onFrame(true);
  machine.onFrame(true);
  machine.onFrame(false);  // a hand in front of the ball
  EXPECT_EQ(machine.goodFramesSoFar(), 0);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kFitLights);
}

TEST(LightingStateMachine, GivesUpAfterMaxFramesAndKeepsRunning) {
  LightingStateMachine machine({.good_frames_needed = 2, .max_frames = 4});
  EXPECT_EQ(machine.onFrame(false), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(false), FrameOutcome::kNothing);
  EXPECT_EQ(machine.onFrame(false), FrameOutcome::kCalibrationFailed);
  EXPECT_EQ(machine.state(), AppState::kRunning);
  EXPECT_EQ(machine.calibrationsFailed(), 1);
  EXPECT_EQ(machine.calibrationsCompleted(), 0);
}

TEST(LightingStateMachine, PressWhileRunningRecalibratesAndPressDuringOneIsIgnored) {
  LightingStateMachine machine({.good_frames_needed = 2, .max_frames = 10});
  machine.onButtonPress();  // during the start-up calibration
  EXPECT_EQ(machine.pressesIgnored(), 1);
  machine.onFrame(true);
  ASSERT_EQ(machine.onFrame(true), FrameOutcome::kFitLights);
  machine.onButtonPress();
  EXPECT_EQ(machine.state(), AppState::kRecalibrating);
  EXPECT_EQ(machine.pressesAccepted(), 1);
  EXPECT_EQ(machine.goodFramesSoFar(), 0);
  machine.onButtonPress();
  machine.onButtonPress();
  EXPECT_EQ(machine.pressesIgnored(), 3);
  machine.onFrame(true);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kFitLights);
  EXPECT_EQ(machine.calibrationsCompleted(), 2);
}

TEST(LightingStateMachine, NonsensePolicyIsClampedToSomethingThatCanFinish) {
  LightingStateMachine machine({.good_frames_needed = 0, .max_frames = -5});
  EXPECT_EQ(machine.policy().good_frames_needed, 1);
  EXPECT_EQ(machine.onFrame(true), FrameOutcome::kFitLights);
}

}  // namespace
}  // namespace probelight
